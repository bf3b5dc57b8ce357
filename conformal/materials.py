"""Elastic constants of the two bodies and their combined values (seed Eqs. 16-17, Kalker 1990 eq. 1.44).

>>> m = Material.steel()
>>> round(m.G, 1), m.nu, m.K
(82000.0, 0.28, 0.0)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from conformal.errors import InputError


def lame_lambda(G: float, nu: float) -> float:
    """Lamé's first constant lambda = 2 G nu / (1 - 2 nu) (N/mm²) of an isotropic body with shear
    modulus G and Poisson's ratio nu (the one place it is computed).

    >>> lame_lambda(82000.0, 0.25)
    82000.0
    """
    return 2.0 * G * nu / (1.0 - 2.0 * nu)


#: the largest shear or Young's modulus of a scene (N/mm²): diamond's G is about 5e5; beyond, the
#: contact modulus and the Hertz sizes leave the float range (G = 1e308)
MAX_MODULUS = 1e9


@dataclass(frozen=True)
class Material:
    """Body 1 and body 2 elastic constants (N/mm², -). Body 1 is the body the normal points into."""

    G1: float
    nu1: float
    G2: float
    nu2: float

    def __post_init__(self):
        for name in ("G1", "G2"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise InputError(f"material: {name} must be a positive number of N/mm², got {v!r}")
        for name in ("nu1", "nu2"):
            v = getattr(self, name)
            if not (math.isfinite(v) and -1.0 < v < 0.5):
                raise InputError(f"material: {name} (Poisson's ratio) must lie in (-1, 0.5), got {v!r}")

    @classmethod
    def identical(cls, G: float, nu: float) -> "Material":
        return cls(G, nu, G, nu)

    @classmethod
    def steel(cls) -> "Material":
        return cls.identical(82000.0, 0.28)

    @property
    def G(self) -> float:
        """Combined shear modulus: 1/G = (1/G1 + 1/G2)/2 (seed Eq. 16)."""
        return 2.0 / (1.0 / self.G1 + 1.0 / self.G2)

    @property
    def nu(self) -> float:
        """Combined Poisson ratio: nu/G = (nu1/G1 + nu2/G2)/2 (seed Eq. 17)."""
        return self.G * 0.5 * (self.nu1 / self.G1 + self.nu2 / self.G2)

    @property
    def K(self) -> float:
        """Difference parameter: K/G = ((1-2nu1)/G1 - (1-2nu2)/G2)/4 (minus sign; K = 0 for identical bodies)."""
        return self.G * 0.25 * ((1 - 2 * self.nu1) / self.G1 - (1 - 2 * self.nu2) / self.G2)

    @property
    def E_star(self) -> float:
        """Contact modulus 1/E* = (1-nu1²)/E1 + (1-nu2²)/E2, which equals G/(1-nu) for the combined constants."""
        return self.G / (1.0 - self.nu)

    @property
    def quasi_identical(self) -> bool:
        return abs(self.K) < 1e-12
