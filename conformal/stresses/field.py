"""Stress fields below a contact patch and their maxima (issue 24, items 1, 3, 4).

A :class:`StressField` holds sigma on a block of points: depth planes below the element centres
of a planar grid, or the lines along the normals below a conformal strip.  Its :meth:`summary`
gives the JSON fields of ``conformal stresses`` (maxima of the von Mises stress, the principal
shear (s1 - s3)/2, the orthogonal shear and the largest principal stress, with their depths and
positions, and the Dang Van index).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError
from conformal.stresses.fatigue import FatigueParameters, dang_van
from conformal.stresses.halfspace import _curved_frames, curved_planes, planar_planes
from conformal.stresses.invariants import max_principal, orthogonal_shear, principal_shear, von_mises

#: default number of depth planes
N_DEPTHS = 40
#: default deepest plane: this many times the smaller semi-axis of the patch (the Hertz maxima of
#: the principal and the orthogonal shear lie at 0.78 b and 0.5 b for a long ellipse, 0.48 a for a
#: circle, Johnson 1985 §3.4, §4.2)
DEPTH_FACTOR = 2.0


@dataclass(frozen=True, eq=False)
class StressField:
    """Stresses (N/mm², tension positive) on a block of points (mm).

    sigma : (nd, n1, n2, 3, 3); points : (nd, n1, n2, 3); depths : (nd,), the depth of each plane
    below the surface; axis 1 is the rolling direction x.  ``frame``: "planar" (the grid's frame,
    z the depth into body 1) or "rail_profile" (a conformal strip: the rail-profile frame, z down).
    ``normal`` (n2, 3): the depth axis below each column (for the orthogonal shear); ``body`` 1 or 2.
    """

    sigma: np.ndarray
    points: np.ndarray
    depths: np.ndarray
    normal: np.ndarray
    frame: str
    body: int = 1

    @property
    def von_mises(self) -> np.ndarray:
        return von_mises(self.sigma)

    @property
    def principal_shear(self) -> np.ndarray:
        return principal_shear(self.sigma)

    @property
    def max_principal(self) -> np.ndarray:
        return max_principal(self.sigma)

    @property
    def orthogonal_shear(self) -> np.ndarray:
        """sigma_xn: x the rolling direction, n the depth axis of each column."""
        n = np.broadcast_to(self.normal[None, None, :, :], self.sigma.shape[:-1])
        return orthogonal_shear(self.sigma, (1.0, 0.0, 0.0), n)

    def _at(self, values: np.ndarray, use_abs: bool = False) -> dict:
        v = np.abs(values) if use_abs else values
        i = np.unravel_index(int(np.nanargmax(v)), v.shape)
        return {"value": float(values[i]), "depth": float(self.depths[i[0]]),
                "position": [float(c) for c in self.points[i]]}

    def summary(self, params: FatigueParameters | None = None) -> dict:
        """Maxima with depth and position (x, y, z in mm, in ``frame``) and the Dang Van index."""
        params = params or FatigueParameters()
        vm = self._at(self.von_mises)
        sh = self._at(self.principal_shear)
        orth = self._at(self.orthogonal_shear, use_abs=True)
        s1 = self._at(self.max_principal)
        tau_dv, _ = dang_van(self.sigma, params.alpha_dv, axis=1)           # (nd, n2)
        dv = np.unravel_index(int(np.nanargmax(tau_dv)), tau_dv.shape)
        per_depth = tau_dv.max(axis=1)
        return {
            "frame": self.frame, "body": self.body,
            "max_von_mises": vm["value"], "max_von_mises_depth": vm["depth"], "max_von_mises_position": vm["position"],
            "max_shear": sh["value"], "max_shear_depth": sh["depth"], "max_shear_position": sh["position"],
            "max_orthogonal_shear": abs(orth["value"]), "max_orthogonal_shear_signed": orth["value"],
            "max_orthogonal_shear_depth": orth["depth"], "max_orthogonal_shear_position": orth["position"],
            "max_principal": s1["value"], "max_principal_depth": s1["depth"], "max_principal_position": s1["position"],
            "dang_van": {"alpha_dv": params.alpha_dv, "tau_e": params.tau_e, "tau_dv_max": float(tau_dv[dv]),
                         "depth": float(self.depths[dv[0]]), "FI_sub": float(tau_dv[dv] - params.tau_e),
                         "per_depth": [[float(d), float(t)] for d, t in zip(self.depths, per_depth)]},
            "depths": {"n": int(self.depths.size), "max": float(self.depths.max()),
                       "step": float(self.depths[1] - self.depths[0]) if self.depths.size > 1 else 0.0},
        }


#: the deepest plane, in larger semi-axes (the stresses there are below 1e-6 of the surface's)
MAX_DEPTH_FACTOR = 1000.0


def default_depths(a: float, b: float, depth: float | None = None, n: int = N_DEPTHS) -> np.ndarray:
    """n depths from 0 to ``depth`` (default DEPTH_FACTOR x the smaller semi-axis)."""
    if depth is None:
        lo = min(a, b) if min(a, b) > 0 else max(a, b)
        if not (lo > 0 and math.isfinite(lo)):
            raise InputError("--depth: the patch has no extent to take a default depth from; give --depth")
        depth = DEPTH_FACTOR * lo
    if not (isinstance(depth, (int, float)) and math.isfinite(depth) and depth > 0):
        raise InputError(f"--depth: must be a positive number of mm, got {depth!r}")
    far = MAX_DEPTH_FACTOR * max(a, b)
    if math.isfinite(far) and far > 0 and depth > far:    # depth = 1e300: the planes' fields overflow (LinAlgError)
        raise InputError(f"--depth: {depth:g} mm is more than {MAX_DEPTH_FACTOR:g} x the larger semi-axis "
                         f"({max(a, b):.3g} mm), where the stresses are below 1e-6 of the surface's; give --depth "
                         f"<= {far:.3g}")
    if not (isinstance(n, int) and 2 <= n <= 2000):
        raise InputError(f"[stresses] n_depths: must be an integer in [2, 2000], got {n!r}")
    return np.linspace(0.0, float(depth), n)


def stress_field(field, depths, *, nu: float, body: int = 1, columns=None) -> StressField:
    """The half-space stress field of a traction field on depth planes (FFT): below the element
    centres of a planar grid, or along the normals of a conformal strip's element centres
    (``columns``: the strip's columns to evaluate, default those with contact)."""
    depths = np.asarray(depths, float).ravel()
    curved = getattr(field, "curved", None)
    if curved is None:
        sig = planar_planes(field, depths, nu=nu, body=body)
        g = field.grid
        X, Y = g.mesh()
        sgn = 1.0 if body == 1 else -1.0
        pts = np.empty(sig.shape[:-1])
        pts[..., 0], pts[..., 1] = X[None], Y[None]
        pts[..., 2] = sgn * depths[:, None, None]
        normal = np.broadcast_to([0.0, 0.0, sgn], (g.my, 3)).copy()
        return StressField(sig, pts, depths, normal, "planar", body)
    if columns is None:
        loaded = np.flatnonzero(np.any(np.asarray(field.side_frame("pn")) > 0, axis=0))
        if loaded.size == 0:
            loaded = np.arange(curved.ms)
        lo, hi = max(int(loaded[0]) - 1, 0), min(int(loaded[-1]) + 2, curved.ms)
        columns = np.arange(lo, hi)
    columns = np.asarray(columns, int)
    sig, pts = curved_planes(field, depths, nu=nu, body=body, columns=columns)
    normal = _curved_frames(curved, body)[columns][:, :, 2]
    return StressField(sig, pts, depths, normal, "rail_profile", body)
