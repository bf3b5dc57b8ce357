"""Contact per wheel for the wheelset model: a contact-geometry table and Hertz with damping.

The profile contact search of :mod:`conformal.geometry.search` (global search of the gap on the
wheel's contact locus, then Newton-Raphson on seed Eqs. 54-55) is run once per lateral shift of
the wheel over its rail (side frame, zero roll and yaw) on a uniform grid.  Every local minimum
of the gap is a contact candidate; the deepest one with a contact angle below
``FLANGE_ANGLE`` is the *tread* patch, the deepest one above it the *flange* patch (a second
contact, two-point contact when both touch).  Per patch the table stores

* ``Z``: the wheelset height (mm, z down) at which that patch touches,
* the inner rail normal (n_y, n_z) (side frame), the lateral distance ``L`` of the wheel point from
  the wheelset centre and the rolling radius ``R`` (mm), the rail contact coordinate ``yc``,
* Hertz: ``Kh`` (F = Kh p^1.5, N/mm^1.5) and the semi-axes ``a1, b1`` at 1 mm approach
  (a = a1 sqrt(p)); both from the principal relative curvatures of the search,
* Kalker's C11, C22, C23, C33 of the ellipse a/b (they depend on the curvatures only).

The Hertz columns (Kh, a1, b1, C11..C33) come from second derivatives of the profile splines,
which carry a row-to-row sampling noise of 1-2 % (b1) and 0.8 % (Kh) on the tread; they are
smoothed by a moving average over +-``SMOOTH`` mm (touching heights, normals and radii are not).
Between grid points the table is interpolated by cubic Hermite polynomials (C1: the contact
potential built on it is differentiable, so the model conserves energy without creep and
damping).  :func:`interpolation_error` measures the interpolation error against fresh searches at
the midpoints.  Yaw is not a table coordinate: a yaw of a few mrad moves the contact point along
the rail by about R psi tan(contact angle) without changing its lateral position to first order.

>>> normal_force(2.0e5, 0.0, 5.0, 1500.0)      # Eq. 57 is zero at zero penetration
0.0
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from conformal.errors import ConformalError, ConvergenceError, InputError, NoContactError
from conformal.geometry.placement import make_pair
from conformal.geometry.profiles import builtin_flange_back, load_profile
from conformal.geometry.search import find_contacts, touch_height
from conformal.geometry.spline import fit_curve
from conformal.materials import Material
from conformal.theories.coefficients import c33 as c33_of, coefficient_arrays
from conformal.theories.hertz import hertz_from_curvatures

FLANGE_ANGLE = 0.35      # rad (20 deg): contacts steeper than this are the flange patch
FAR = 20.0               # mm: Z of the flange patch where it has no local minimum (no contact)
COLUMNS = ("Z", "ny", "nz", "L", "R", "yc", "Kh", "a1", "b1", "c11", "c22", "c23", "c33")
C = {name: i for i, name in enumerate(COLUMNS)}
NC = len(COLUMNS)
SLOTS = ("tread", "flange")
HERTZ = [C[k] for k in ("Kh", "a1", "b1", "c11", "c22", "c23", "c33")]
SMOOTH = 0.5             # mm: half-width of the moving average of the Hertz columns (see below)


@dataclass(frozen=True, eq=False)
class ContactGeometry:
    """Inputs of the table: profiles, track and wheelset geometry, material (mm, N/mm^2)."""

    wheel_profile: str
    rail_profile: str
    rail_cant: float
    gauge: float
    gauge_height: float
    wheel_radius: float
    flange_back: float
    flange_back_pos: float | None
    material: Material
    base_dir: str = "."

    def key(self) -> tuple:
        m = self.material
        return (self.wheel_profile, self.rail_profile, self.rail_cant, self.gauge, self.gauge_height,
                self.wheel_radius, self.flange_back, self.flange_back_pos, m.G1, m.nu1, m.G2, m.nu2,
                str(self.base_dir))


@dataclass(frozen=True, eq=False)
class ContactTable:
    """Patch data on a uniform grid of lateral shift y (side frame, mm): ``data[i, slot, column]``."""

    y0: float
    step: float
    data: np.ndarray          # (n, 2, NC)
    slopes: np.ndarray        # (n, 2, NC), d/dy (per mm)
    flange_valid: np.ndarray  # (n,) bool: a flange patch (local minimum) exists
    geometry: ContactGeometry
    build_s: float = 0.0

    @property
    def y(self) -> np.ndarray:
        return self.y0 + self.step * np.arange(self.data.shape[0])

    @property
    def y_max(self) -> float:
        return self.y0 + self.step * (self.data.shape[0] - 1)

    def evaluate(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values and y-derivatives (shape (len(y), 2, NC)) at lateral shifts y (mm), cubic Hermite."""
        y = np.asarray(y, dtype=float)
        t = (y - self.y0) / self.step
        n = self.data.shape[0]
        if np.any(t < 0) or np.any(t > n - 1) or not np.all(np.isfinite(t)):
            bad = float(y[np.argmax(np.abs(y))]) if np.all(np.isfinite(y)) else float("nan")
            raise ConvergenceError(f"wheelset dynamics: a wheel's lateral shift {bad:.2f} mm left the contact "
                                   f"table ({self.y0:.1f} .. {self.y_max:.1f} mm): flange climbing or "
                                   "derailment (or raise [contact] table_range)")
        i = np.minimum(t.astype(int), n - 2)
        s = (t - i)[:, None, None]
        f0, f1 = self.data[i], self.data[i + 1]
        m0, m1 = self.slopes[i] * self.step, self.slopes[i + 1] * self.step
        s2, s3 = s * s, s * s * s
        val = (2 * s3 - 3 * s2 + 1) * f0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * f1 + (s3 - s2) * m1
        der = ((6 * s2 - 6 * s) * f0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * f1
               + (3 * s2 - 2 * s) * m1) / self.step
        return val, der


def normal_force(Kh, p, pdot, damping):
    """Hertz normal force with damping (seed Eq. 57), N, never negative.

    F = Kh p^1.5 + C pdot p for an overlap p > 0 (mm; the seed's delta = -p: its Eq. 56 uses
    the outer normal), pdot in mm/s, C in N s/mm^2; 0 without overlap.  The factor p in the
    damping term makes the force vanish at zero penetration (the seed's reason for |delta|).

    >>> round(normal_force(1.0e5, 0.04, 0.0, 0.0), 6)     # Kh p^1.5
    800.0
    """
    p = np.asarray(p, dtype=float)
    pp = np.maximum(p, 0.0)
    f = np.asarray(Kh) * pp * np.sqrt(pp) + np.asarray(damping) * np.asarray(pdot) * pp   # Eq. 57
    f = np.where(p > 0, np.maximum(f, 0.0), 0.0)
    return float(f) if f.ndim == 0 else f


def _curves(g: ContactGeometry):
    from conformal.scene import FLANGEWAY

    play = g.gauge - g.flange_back
    if not FLANGEWAY[0] <= play <= FLANGEWAY[1]:     # as the contact scene's [geometry] gauge check
        raise InputError(f"[track] gauge: gauge - flange_back = {g.gauge:g} - {g.flange_back:g} = {play:g} mm must "
                         f"lie within {FLANGEWAY[0]:g} to {FLANGEWAY[1]:g} mm ([wheels] flange_back; both in mm): "
                         "otherwise the wheels do not lie over their rails")
    w = load_profile(g.wheel_profile, "wheel", g.base_dir)
    r = load_profile(g.rail_profile, "rail", g.base_dir)
    rho_min = float(g.wheel_radius) + float(w.points[:, 1].min())
    if rho_min <= 0.0:
        raise InputError(f"[wheels] wheel_radius: {g.wheel_radius:g} mm leaves the wheel profile {w.name} a radius of "
                         f"{rho_min:.3g} mm at its highest point; the radius at the profile origin is in mm")
    fbp = g.flange_back_pos if g.flange_back_pos is not None else builtin_flange_back(g.wheel_profile)
    return fit_curve(w.points, name=w.name), fit_curve(r.points, name=r.name), fbp


def _hertz_row(A: float, B: float, material: Material) -> tuple[float, float, float, float, float, float, float]:
    if not (A > 0 and B > 0):
        raise InputError(f"contact table: the relative curvatures A = {A:.3g}, B = {B:.3g} 1/mm are not "
                         "both positive (a conformal patch): Hertz does not apply")
    h = hertz_from_curvatures(A, B, material, approach=1.0)
    c11, c22, c23 = (float(v) for v in coefficient_arrays(h.a / h.b, material.nu))
    try:
        c33 = float(c33_of(h.a / h.b, material.nu))
    except ConformalError:
        c33 = float("nan")
    return h.FN, h.a, h.b, c11, c22, c23, c33


def search_row(geom: ContactGeometry, curves, y: float) -> tuple[np.ndarray, bool]:
    """Patch data (2, NC) at lateral shift y (side frame, mm) by a fresh contact search."""
    wc, rc, fbp = curves
    pair = make_pair(wc, rc, side="right", placement="wheelset", lateral_shift=float(y), roll=0.0, yaw=0.0,
                     rail_cant=geom.rail_cant, gauge=geom.gauge, gauge_height=geom.gauge_height,
                     flange_back=geom.flange_back, flange_back_pos=fbp, wheel_radius=geom.wheel_radius)
    z_t, _ = touch_height(pair)
    sr = find_contacts(pair.wheel(z_t), pair.rail, window=30.0)
    best: list = [None, None]
    for c in sr.contacts:
        slot = 1 if abs(c.delta) > FLANGE_ANGLE else 0
        if best[slot] is None or c.penetration > best[slot].penetration:
            best[slot] = c
    row = np.full((2, NC), np.nan)
    for slot, c in enumerate(best):
        if c is None:
            continue
        A, B, _ = c.principal()
        Kh, a1, b1, c11, c22, c23, c33 = _hertz_row(A, B, geom.material)
        Z = z_t - c.penetration / c.normal[2]
        yc = float(pair.rail.to_own(np.array(c.rail_point[1:]))[0])
        row[slot] = (Z, c.normal[1], c.normal[2], c.wheel_point[1] - y, c.rolling_radius, yc,
                     Kh, a1, b1, c11, c22, c23, c33)
    if best[0] is None:
        raise NoContactError(f"contact table: no tread contact at lateral shift {y:.2f} mm "
                             f"(only a flange contact, contact angle above {FLANGE_ANGLE} rad)")
    return row, best[1] is not None


#: most rows of a contact table (one contact search each; the default 0.1 mm over +-14 mm has 281)
MAX_TABLE_ROWS = 20_001


def check_table_size(step: float, y_range: float) -> int:
    """Rows of a table of ``step`` over -y_range..y_range (mm); InputError naming the key when a
    value is not a positive finite number or the table would have more than MAX_TABLE_ROWS rows."""
    if not (math.isfinite(step) and step > 0 and math.isfinite(y_range) and y_range > 0):
        raise InputError(f"[contact] table_step, table_range: must be finite and > 0, got {step}, {y_range}")
    rows = 2.0 * y_range / step + 1.0
    if rows > MAX_TABLE_ROWS:
        raise InputError(f"[contact] table_step: {step:g} mm over +-{y_range:g} mm (table_range) is {rows:.3g} "
                         f"rows of contact searches, more than {MAX_TABLE_ROWS}; use table_step >= "
                         f"{2.0 * y_range / (MAX_TABLE_ROWS - 1):.2g} mm")
    return int(round(2 * y_range / step)) + 1


def build_table(geom: ContactGeometry, step: float = 0.1, y_range: float = 14.0) -> ContactTable:
    """Search the contacts on a uniform grid -y_range..y_range (mm) and assemble the table.

    >>> from conformal.materials import Material
    >>> g = ContactGeometry("APTA140", "UIC60", 0.025, 1435.0, 15.875, 473.8, 1353.8, None,
    ...                     Material.identical(82031.0, 0.28))
    >>> t = build_table(g, step=0.5, y_range=2.0)
    >>> round(float((t.data[-1, 0, C["R"]] - t.data[0, 0, C["R"]]) / 4.0), 4)   # 1:40 cone
    0.025
    """
    import time

    n = check_table_size(step, y_range)
    t0 = time.perf_counter()
    curves = _curves(geom)
    ys = -y_range + step * np.arange(n)
    data = np.empty((n, 2, NC))
    valid = np.zeros(n, bool)
    for k, y in enumerate(ys):
        data[k], valid[k] = search_row(geom, curves, float(y))
    # the flange patch where it has no local minimum: far away (no contact), data of the nearest row
    if valid.any():
        idx = np.nonzero(valid)[0]
        for k in np.nonzero(~valid)[0]:
            j = idx[np.argmin(np.abs(idx - k))]
            data[k, 1] = data[j, 1]
            data[k, 1, C["Z"]] = data[k, 0, C["Z"]] + FAR
    else:
        data[:, 1] = data[:, 0]
        data[:, 1, C["Z"]] += FAR
    for slot in range(2):       # C33 beyond its table: the nearest finite value
        col = data[:, slot, C["c33"]]
        if not np.all(np.isfinite(col)):
            if not np.isfinite(col).any():
                raise InputError("contact table: C33 is unavailable for every patch (conformal/data/kalker_c33.csv)")
            good = np.nonzero(np.isfinite(col))[0]
            for k in np.nonzero(~np.isfinite(col))[0]:
                col[k] = col[good[np.argmin(np.abs(good - k))]]
    for slot, rows in ((0, np.ones(n, bool)), (1, valid)):
        for a, b in _runs(rows):
            data[a:b, slot, HERTZ] = _moving_average(data[a:b, slot, HERTZ], int(round(SMOOTH / step)))
    slopes = np.gradient(data, step, axis=0)
    # flange slot: slopes within each run of rows that have a flange patch (one-sided at the ends),
    # zero on the filled rows, so that the filled values do not leak into the valid cells
    slopes[:, 1] = 0.0
    k = 0
    while k < n:
        if not valid[k]:
            k += 1
            continue
        j = k
        while j + 1 < n and valid[j + 1]:
            j += 1
        if j > k:
            slopes[k:j + 1, 1] = np.gradient(data[k:j + 1, 1], step, axis=0)
        k = j + 1
    return ContactTable(float(ys[0]), float(step), data, slopes, valid, geom, time.perf_counter() - t0)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) of the runs of True in mask."""
    out, k, n = [], 0, mask.size
    while k < n:
        if mask[k]:
            j = k
            while j < n and mask[j]:
                j += 1
            out.append((k, j))
            k = j
        else:
            k += 1
    return out


def _moving_average(v: np.ndarray, h: int) -> np.ndarray:
    """Centred moving average over +-h rows (the window shrinks symmetrically at the ends)."""
    if h < 1 or v.shape[0] < 3:
        return v
    n = v.shape[0]
    c = np.concatenate([np.zeros((1,) + v.shape[1:]), np.cumsum(v, axis=0)])
    i = np.arange(n)
    w = np.minimum(np.minimum(i, n - 1 - i), h)
    return (c[i + w + 1] - c[i - w]) / (2 * w + 1)[:, None]


@lru_cache(maxsize=8)
def _cached(key, geom: ContactGeometry, step: float, y_range: float) -> ContactTable:
    return build_table(geom, step, y_range)


def cached_table(geom: ContactGeometry, step: float, y_range: float) -> ContactTable:
    """:func:`build_table`, memoised per geometry (tables take about 10 ms per grid point)."""
    return _cached((geom.key(), float(step), float(y_range)), geom, float(step), float(y_range))


@dataclass(frozen=True)
class InterpolationError:
    """Largest differences table - fresh search at grid midpoints, per patch (tread, flange)."""

    Z_mm: tuple[float, float]       # touching height: enters the overlap p directly
    R_mm: tuple[float, float]       # rolling radius
    normal: tuple[float, float]     # components of the unit normal
    L_mm: tuple[float, float]       # lateral position of the contact point
    n_points: int

    def as_dict(self) -> dict:
        return {f"{k}_{slot}": getattr(self, k)[i] for k in ("Z_mm", "R_mm", "normal", "L_mm")
                for i, slot in enumerate(SLOTS)} | {"n_points": self.n_points}


def interpolation_error(table: ContactTable, n_points: int = 24) -> InterpolationError:
    """Compare the interpolated table with fresh contact searches at ``n_points`` grid midpoints
    spread over the table and, for the flange, at every midpoint of the flange rows."""
    curves = _curves(table.geometry)
    ys = table.y
    mids = 0.5 * (ys[:-1] + ys[1:])
    pick = np.linspace(0, mids.size - 1, min(n_points, mids.size)).round().astype(int)
    fl = np.nonzero(table.flange_valid[:-1] & table.flange_valid[1:])[0]
    pick = np.unique(np.concatenate([pick, fl[:: max(1, fl.size // n_points)]]))
    err = np.zeros((2, 4))
    for k in pick:
        row, has_flange = search_row(table.geometry, curves, float(mids[k]))
        val, _ = table.evaluate(np.array([mids[k]]))
        slots = [0]
        if has_flange and table.flange_valid[k] and table.flange_valid[k + 1]:
            slots.append(1)
        for s in slots:
            d = np.abs(val[0, s] - row[s])
            err[s] = np.maximum(err[s], [d[C["Z"]], d[C["R"]], max(d[C["ny"]], d[C["nz"]]), d[C["L"]]])
    e = [tuple(float(v) for v in err[:, i]) for i in range(4)]
    return InterpolationError(e[0], e[1], e[2], e[3], int(pick.size))
