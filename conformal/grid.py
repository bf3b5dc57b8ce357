"""Potential contact grids.

A planar grid is a rectangle [xl, xl + mx dx] x [yl, yl + my dy] of mx x my equal elements.
Arrays on the grid have shape (mx, my) and are indexed [ix, iy] (x = rolling direction first);
element (ix, iy) has its centre at x = xl + (ix + 1/2) dx, y = yl + (iy + 1/2) dy (CONTACT's
convention with 0-based indices).  Rolling is in +x: material enters at the leading edge x = xh.

>>> g = PlanarGrid(mx=4, my=2, dx=0.5, dy=1.0, xl=-1.0, yl=-1.0)
>>> g.x.tolist(), g.y.tolist(), g.shape, g.area
([-0.75, -0.25, 0.25, 0.75], [-0.5, 0.5], (4, 2), 0.5)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from conformal.errors import InputError


@dataclass(frozen=True)
class PlanarGrid:
    mx: int
    my: int
    dx: float
    dy: float
    xl: float
    yl: float

    def __post_init__(self):
        if self.mx < 1 or self.my < 1:
            raise InputError(f"[grid] mx, my: need at least one element, got {self.mx} x {self.my}")
        if not (self.dx > 0 and self.dy > 0):
            raise InputError(f"[grid] dx, dy: must be > 0, got {self.dx}, {self.dy}")

    @classmethod
    def centred(cls, mx: int, my: int, dx: float, dy: float) -> "PlanarGrid":
        return cls(mx, my, dx, dy, -0.5 * mx * dx, -0.5 * my * dy)

    @classmethod
    def around_ellipse(cls, a: float, b: float, n: int = 40, scale: float = 1.1,
                       mx: int | None = None, my: int | None = None) -> "PlanarGrid":
        """n x n elements (or mx x my) on [-scale a, scale a] x [-scale b, scale b]."""
        mx, my = mx or n, my or n
        return cls.centred(mx, my, 2 * scale * a / mx, 2 * scale * b / my)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.mx, self.my)

    @property
    def size(self) -> int:
        return self.mx * self.my

    @property
    def area(self) -> float:
        """Area of one element, mm²."""
        return self.dx * self.dy

    @property
    def x(self) -> np.ndarray:
        return self.xl + (np.arange(self.mx) + 0.5) * self.dx

    @property
    def y(self) -> np.ndarray:
        return self.yl + (np.arange(self.my) + 0.5) * self.dy

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Element centres as two (mx, my) arrays."""
        return np.meshgrid(self.x, self.y, indexing="ij")
