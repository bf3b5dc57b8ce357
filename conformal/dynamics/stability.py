"""Hunting stability of the suspended wheelset: linear eigenvalues and nonlinear onset.

**Linear model** (``method = "linear"``): the wheelset's lateral and yaw motion linearised about
centred running, with the creep coefficients of Kalker's linear theory at the centred contact
(f11 = G ab C11, f22 = G ab C22, f23 = G (ab)^1.5 C23, f33 = G (ab)^2 C33, SI units), the
equivalent conicity lambda = dr/dy (a secant over +-1 mm), the rolling radius r0 and the contact half-distance l0 from
the contact table; the roll follows the geometric constraint phi = sigma y (sigma = Z'(0)/l0,
from the touching heights) and enters the spin creepage, the lateral creepage (-r0 phi'/V) and
the gyroscopic yaw couple Iyy (V/r0) phi'; the contact angle's slope t' = d(n_y/n_z)/dy gives the
gravitational stiffness 2 W t'.  With state x = (y, psi, y', psi'):

    m y''     = -2 f22 ((1 - r0 sigma) y'/V - psi) + 2 f23 (t' + sigma) y / r0 - 2 f23 psi'/V
                - (2 ky + 2 W t') y - 2 cy y'
    Izz psi'' = -2 f11 l0 (lambda y / r0 + l0 psi'/V) + 2 f23 ((1 - r0 sigma) y'/V - psi)
                + 2 f33 ((t' + sigma) y / r0 - psi'/V) + Iyy (V/r0) sigma y'
                - 2 l0 f23 t0/r0 psi - 2 kx b^2 psi - 2 cx b^2 psi'

(the same terms the nonlinear model of :mod:`conformal.dynamics.model` has with creep model
``linear``, to first order).  The critical speed is the lowest speed where an eigenvalue crosses
into the right half plane.

**Nonlinear** (``method = "nonlinear"``): the lowest speed at which the full model's response to
the scene's initial lateral disturbance (no track irregularity) no longer decays, by bisection.

>>> from conformal.dynamics.scene import EXAMPLE, scene_from_dict
>>> import tomllib
>>> s = scene_from_dict(tomllib.loads(EXAMPLE))
>>> lin = linear_inputs(s, table_step=0.5, table_range=2.0)
>>> round(lin.equivalent_conicity, 4), round(lin.rolling_radius, 4)
(0.025, 0.4572)
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np
from scipy.integrate import solve_ivp

from conformal.dynamics.contact import C, ContactGeometry, cached_table
from conformal.dynamics.scene import MAX_SPEED as MAX_SPEED  # re-exported: the --v-max bound (one eigenproblem per m/s)
from conformal.dynamics.scene import Irregularity, VehicleScene
from conformal.errors import ConvergenceError, InputError


SECANT = 1.0      # mm: conicity, contact-angle slope and roll slope are secants over +-1 mm


@dataclass(frozen=True)
class LinearInputs:
    """Inputs of the linear model (SI): creep coefficients, geometry and the vehicle."""

    f11: float                    # N
    f22: float                    # N
    f23: float                    # N m
    f33: float                    # N m^2
    equivalent_conicity: float    # -
    rolling_radius: float         # m
    contact_half_distance: float  # m
    sigma: float                  # roll per lateral displacement (rad/m)
    contact_angle_slope: float    # t' = d(n_y/n_z)/dy (1/m)
    t0: float                     # n_y/n_z at centred running
    a: float                      # m
    b: float                      # m
    m: float
    Izz: float
    Iyy: float
    W: float
    kx: float
    ky: float
    cx: float
    cy: float
    half_spacing: float

    def as_dict(self) -> dict:
        return asdict(self)


def linear_inputs(scene: VehicleScene, *, table_step: float | None = None,
                  table_range: float | None = None) -> LinearInputs:
    """Linear-model inputs of the scene from its contact table at centred running."""
    tr, wh, ct, v = scene.track, scene.wheels, scene.contact, scene.vehicle
    geom = ContactGeometry(wh.wheel_profile, tr.rail_profile, tr.rail_cant, tr.gauge, tr.gauge_height,
                           wh.wheel_radius, wh.flange_back, wh.flange_back_pos, scene.material, scene.base_dir)
    table = cached_table(geom, table_step or ct.table_step, table_range or ct.table_range)
    h = min(SECANT, table.y_max)                      # secants over +-h mm: robust to table noise
    val, _ = table.evaluate(np.array([-h, 0.0, h]))
    row, lo, hi = val[1, 0], val[0, 0], val[2, 0]
    r0, l0 = float(row[C["R"]]) / 1000.0, float(row[C["L"]]) / 1000.0
    lam = float(hi[C["R"]] - lo[C["R"]]) / (2 * h)
    t0 = float(row[C["ny"]] / row[C["nz"]])
    tp = float(hi[C["ny"]] / hi[C["nz"]] - lo[C["ny"]] / lo[C["nz"]]) / (2 * h) * 1000.0
    sigma = float(hi[C["Z"]] - lo[C["Z"]]) / (2 * h) / l0
    p0 = (v.wheel_load / (row[C["Kh"]] * row[C["nz"]])) ** (2.0 / 3.0)
    a, b = float(row[C["a1"]]) * math.sqrt(p0) / 1000.0, float(row[C["b1"]]) * math.sqrt(p0) / 1000.0
    G = scene.material.G * 1e6
    ab = a * b
    c11, c22, c23, c33 = (float(row[C[k]]) for k in ("c11", "c22", "c23", "c33"))
    return LinearInputs(f11=G * ab * c11, f22=G * ab * c22, f23=G * ab**1.5 * c23, f33=G * ab**2 * c33, equivalent_conicity=lam, rolling_radius=r0,
                        contact_half_distance=l0, sigma=sigma, contact_angle_slope=float(tp), t0=float(t0),
                        a=a, b=b, m=v.mass, Izz=v.Izz, Iyy=v.Iyy, W=v.wheel_load, kx=v.kx, ky=v.ky, cx=v.cx,
                        cy=v.cy, half_spacing=0.5 * v.spring_spacing)


def linear_matrix(p: LinearInputs, V: float) -> np.ndarray:
    """State matrix of x = (y, psi, y', psi') at speed V (m/s) (see the module docstring)."""
    if not V > 0:
        raise InputError(f"linear model: speed must be > 0, got {V!r}")
    r0, l0, lam, s, tp = p.rolling_radius, p.contact_half_distance, p.equivalent_conicity, p.sigma, p.contact_angle_slope
    b2 = p.half_spacing**2
    e = 1.0 - r0 * s
    lat = [2 * p.f23 * (tp + s) / r0 - 2 * p.ky - 2 * p.W * tp, 2 * p.f22,
           -2 * p.f22 * e / V - 2 * p.cy, -2 * p.f23 / V]
    yaw = [-2 * p.f11 * l0 * lam / r0 + 2 * p.f33 * (tp + s) / r0,
           -2 * p.f23 - 2 * p.kx * b2 - 2 * l0 * p.f23 * p.t0 / r0,
           2 * p.f23 * e / V + p.Iyy * V / r0 * s,
           -2 * p.f11 * l0**2 / V - 2 * p.f33 / V - 2 * p.cx * b2]
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2] = np.array(lat) / p.m
    A[3] = np.array(yaw) / p.Izz
    return A


def hunting_mode(p: LinearInputs, V: float) -> tuple[float, float, float]:
    """(largest real part 1/s, its frequency Hz, damping ratio) of the linear model at V."""
    ev = np.linalg.eigvals(linear_matrix(p, V))
    k = int(np.argmax(ev.real))
    lam = ev[k]
    return float(lam.real), float(abs(lam.imag) / (2 * math.pi)), float(-lam.real / abs(lam))


def linear_critical_speed(p: LinearInputs, v_max: float = 300.0, dv: float = 1.0) -> float | None:
    """Critical hunting speed of the linear model.

    Parameters
    ----------
    p : LinearInputs
        From :func:`linear_inputs`.
    v_max, dv : float
        Speeds dv, 2 dv, ... v_max (m/s) are scanned for an eigenvalue with a positive real
        part; the first crossing is refined by bisection to 1e-6 m/s.

    Returns
    -------
    float or None
        The lowest unstable speed (m/s); None if stable up to v_max; dv if unstable from the start.

    Examples
    --------
    >>> from conformal.dynamics.scene import EXAMPLE, scene_from_dict
    >>> import tomllib
    >>> p = linear_inputs(scene_from_dict(tomllib.loads(EXAMPLE)), table_step=0.5, table_range=2.0)
    >>> round(linear_critical_speed(p), 1)
    71.3
    """
    speeds = np.arange(dv, v_max + dv, dv)
    re = np.array([hunting_mode(p, V)[0] for V in speeds])
    idx = np.nonzero(re > 0)[0]
    if idx.size == 0:
        return None
    k = int(idx[0])
    if k == 0:
        return float(speeds[0])
    lo, hi = float(speeds[k - 1]), float(speeds[k])
    while hi - lo > 1e-6:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if hunting_mode(p, mid)[0] <= 0 else (lo, mid)
    return 0.5 * (lo + hi)


def linear_growth_time_domain(p: LinearInputs, V: float, cycles: float = 30.0) -> float:
    """Growth rate (1/s, > 0 growing) of the linear model's lateral response at V found by time
    integration (RK45 of x' = A x from y = 1 mm, no eigenvalues): a least-squares line through
    the logarithm of the peaks of |y| in the second half of the run."""
    A = linear_matrix(p, V)
    w = max(V * math.sqrt(max(p.equivalent_conicity, 1e-6) / (p.rolling_radius * p.contact_half_distance)), 1.0)
    T = cycles * 2 * math.pi / w
    n = int(cycles * 40)
    t = np.linspace(0.0, T, n + 1)
    sol = solve_ivp(lambda _t, x: A @ x, (0.0, T), [1e-3, 0.0, 0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-16,
                    method="RK45")
    y = np.abs(sol.y[0])
    half = t >= 0.5 * T
    tt, yy = t[half], y[half]
    i = np.nonzero((yy[1:-1] > yy[:-2]) & (yy[1:-1] >= yy[2:]))[0] + 1
    if i.size < 3:
        return float(np.log(yy[-1] / yy[0]) / (tt[-1] - tt[0]))
    return float(np.polyfit(tt[i], np.log(yy[i]), 1)[0])


def linear_onset_time_domain(p: LinearInputs, lo: float, hi: float, tol: float = 0.01) -> float:
    """Speed (m/s) where the time-domain growth rate of the linear model changes sign, by the
    Illinois variant of regula falsi in [lo, hi] (decaying at lo, growing at hi) until the
    bracket or the step is below ``tol`` m/s."""
    g_lo, g_hi = linear_growth_time_domain(p, lo), linear_growth_time_domain(p, hi)
    if not (g_lo < 0 < g_hi):
        raise InputError(f"linear onset: no sign change of the growth rate between {lo} and {hi} m/s "
                         f"({g_lo:.3g}, {g_hi:.3g} 1/s)")
    side = 0
    mid = lo
    for _ in range(60):
        new = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
        if abs(new - mid) < tol or hi - lo < tol:
            return new
        mid = new
        g = linear_growth_time_domain(p, mid)
        if g < 0:
            lo, g_lo = mid, g
            if side == -1:
                g_hi *= 0.5
            side = -1
        else:
            hi, g_hi = mid, g
            if side == 1:
                g_lo *= 0.5
            side = 1
    return mid


def nonlinear_decays(scene: VehicleScene, V: float, t_end: float | None = None) -> tuple[bool, float | None]:
    """Simulate the full model at V from the scene's initial disturbance without irregularity;
    (decays, decay rate 1/s)."""
    from conformal.dynamics.simulate import simulate

    sim = scene.simulation
    y0 = sim.initial_lateral if sim.initial_lateral != 0.0 else 3.0
    s = replace(scene, track=replace(scene.track, irregularity=Irregularity()),
                simulation=replace(sim, speed=float(V), initial_lateral=y0,
                                   t_end=float(t_end or sim.t_end), output_step=2e-3))
    try:
        r = simulate(s)
    except ConvergenceError:          # the growing motion left the contact table (flange climb)
        return False, None
    rate = r.summary["decay_rate"]
    y = r.history["y"]
    if rate is None:
        return bool(abs(y[-1]) < abs(y[0])), None
    return bool(rate > 0), rate


#: most time-domain runs of the nonlinear bisection (each is a simulation of seconds)
MAX_BISECTIONS = 20


def check_bisection(lo: float, hi: float, tol: float) -> int:
    """The number of halvings that bring [lo, hi] below ``tol`` (m/s); InputError naming --tol when
    tol is not > 0 or needs more than MAX_BISECTIONS time-domain runs."""
    if not (math.isfinite(tol) and tol > 0):
        raise InputError(f"--tol: the bisection tolerance must be > 0 m/s, got {tol}")
    n = max(0, math.ceil(math.log2(max(hi - lo, tol) / tol)))
    if n > MAX_BISECTIONS:
        raise InputError(f"--tol: {tol:g} m/s on [{lo:g}, {hi:g}] m/s needs {n} time-domain runs, more than "
                         f"{MAX_BISECTIONS}; use --tol >= {(hi - lo) / 2 ** MAX_BISECTIONS:.2g}")
    return n


def nonlinear_critical_speed(scene: VehicleScene, lo: float, hi: float, tol: float = 0.5,
                             t_end: float | None = None, log=None) -> tuple[float | None, list]:
    """Bisection for the lowest speed where the disturbance no longer decays; (speed or None if it
    decays at hi, the list of (speed, decays, rate) tried)."""
    n_max = check_bisection(lo, hi, tol)
    tried = []

    def run(V):
        d, rate = nonlinear_decays(scene, V, t_end)
        tried.append((V, d, rate))
        if log:
            log(f"nonlinear: V = {V:.2f} m/s: {'decays' if d else 'does not decay'} (rate {rate})")
        return d

    if run(hi):
        return None, tried
    if not run(lo):
        return lo, tried
    for _ in range(n_max):                 # hi - lo halves each time: below tol after n_max runs
        if hi - lo <= tol:
            break
        mid = 0.5 * (lo + hi)
        if run(mid):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi), tried


def damping_curve(p: LinearInputs, speeds) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(speeds, damping ratio, frequency Hz) of the least-damped mode."""
    sp = np.asarray(speeds, float)
    out = np.array([hunting_mode(p, V) for V in sp])
    return sp, out[:, 2], out[:, 1]
