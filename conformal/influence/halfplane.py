"""Influence numbers of two elastic half-planes (line contact, B = 0) on a row of elements along
x: the operator of :mod:`conformal.solvers.line` (equations in that module's docstring; Johnson
1985, eqs. 2.19, 2.25).

>>> import numpy as np
>>> from conformal.materials import Material
>>> K = halfplane_kernel(4, 0.1, Material.identical(80000.0, 0.3), 10.0)
>>> K.shape, bool(np.allclose(K[..., 0, 0], K[..., 2, 2]))
((7, 1, 1, 3, 3), True)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError
from conformal.grid import PlanarGrid
from conformal.influence.curved import CurvedInfluence
from conformal.materials import Material

#: the reference length L of the half-plane's logarithm, in grid lengths (mx dx)
REFERENCE_FACTOR = 2.0
#: element width across the line (mm): forces are per mm of line length
UNIT_WIDTH = 1.0


def _F(t: np.ndarray) -> np.ndarray:
    """t ln|t| - t, with 0 at t = 0."""
    at = np.abs(t)
    return np.where(at > 0, t * np.log(np.where(at > 0, at, 1.0)), 0.0) - t


def halfplane_kernel(mx: int, dx: float, material: Material, ref_length: float) -> np.ndarray:
    """The x-invariant kernel (2mx-1, 1, 1, 3, 3) of a row of mx elements of length dx on two
    elastic half-planes (module docstring), components (x, y, n)."""
    if not (int(mx) >= 1 and dx > 0 and ref_length > 0):
        raise InputError(f"line contact: need mx >= 1, dx > 0, L > 0 (got {mx}, {dx}, {ref_length})")
    x = np.arange(-(mx - 1), mx) * float(dx)
    h = 0.5 * float(dx)
    base = -(_F(x + h) - _F(x - h) - dx * math.log(ref_length)) * (2.0 / math.pi)
    K = np.zeros((2 * mx - 1, 1, 1, 3, 3))
    E_star = material.G / (1.0 - material.nu)
    K[:, 0, 0, 0, 0] = base / E_star     # u_x from p_x: plane strain
    K[:, 0, 0, 2, 2] = base / E_star     # u_n from p_n
    K[:, 0, 0, 1, 1] = base / material.G  # u_y from p_y: anti-plane shear
    if material.K != 0.0:                 # dissimilar bodies (module docstring)
        coupling = -(material.K / material.G) * 2.0 * np.clip(x, -h, h)
        K[:, 0, 0, 0, 2] = coupling       # u_x from p_n
        K[:, 0, 0, 2, 0] = -coupling      # u_n from p_x
    return K


@dataclass(frozen=True, eq=False)
class LineInfluence(CurvedInfluence):
    """The half-plane operator of a row of elements (ms = 1), with the material's G, nu, K and the
    reference length L (mm), the element length dx (mm) and the material (for :meth:`extended`)."""

    G: float = 0.0
    nu: float = 0.0
    K: float = 0.0
    ref_length: float = 0.0
    dx: float = 0.0
    material: Material | None = None

    @classmethod
    def for_grid(cls, grid: PlanarGrid, material: Material, ref_length: float | None = None) -> "LineInfluence":
        if grid.my != 1:
            raise InputError(f"line contact: the grid has one element across the line (my = 1), got my = {grid.my}")
        L = REFERENCE_FACTOR * grid.mx * grid.dx if ref_length is None else float(ref_length)
        op = cls.from_kernel(halfplane_kernel(grid.mx, grid.dx, material, L))
        for k, v in (("G", material.G), ("nu", material.nu), ("K", material.K), ("ref_length", L),
                     ("dx", grid.dx)):
            object.__setattr__(op, k, float(v))
        object.__setattr__(op, "material", material)
        return op

    def contact_modulus(self) -> float:
        """E* = G / (1 - nu) of the combined constants (N/mm²)."""
        return self.G / (1.0 - self.nu)

    def extended(self, ncols: int) -> "LineInfluence":
        """The same numbers (same reference length) on a row ``ncols`` elements longer."""
        grid = PlanarGrid(self.mx + int(ncols), 1, self.dx, UNIT_WIDTH, 0.0, -0.5 * UNIT_WIDTH)
        return LineInfluence.for_grid(grid, self.material, ref_length=self.ref_length)
