"""Half-space influence numbers for piecewise-constant tractions on rectangles (Love 1929, Kalker 1990).

``A[..., i, j]`` is the displacement difference u_i = u_i(body 1) - u_i(body 2) at an offset (x, y)
from the centre of a dx x dy rectangle loaded by a unit uniform traction p_j on body 1.
Components are ordered (x, y, z) = (0, 1, 2), z = n pointing into body 1.  Displacements are
collocated at element centres (CONTACT's convention), which makes the grid matrix symmetric
(reciprocity A_ij(x, y) = A_ji(-x, -y)).  Closed forms: ../shared/reference/halfspace_influence.md.

On a uniform grid the numbers depend only on the index offset (block Toeplitz), so products are
zero-padded FFT convolutions (DC-FFT, Liu, Wang & Liu 2000): O(N log N), no N x N matrix.

>>> import numpy as np
>>> A = rectangle_influence(np.array(0.0), np.array(0.0), 1.0, 1.0, G=1.0, nu=0.28, K=0.1)
>>> round(float(A[2, 2]), 12)    # 4 (1-nu) asinh(1) / pi, reference Table 1
0.807983787368
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import fft as sfft

from conformal.materials import Material

X, Y, Z = 0, 1, 2


# ------------------------------------------------------------------ closed forms (reference §3)
def _primitives(a: np.ndarray, b: np.ndarray):
    """Corner primitives L1, L2, R, T1, T2 (reference §3.1), with the stated zero conventions."""
    aa, ab = np.abs(a), np.abs(b)
    r = np.hypot(a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        L1 = np.where(aa > 0, a * np.arcsinh(b / np.where(aa > 0, aa, 1.0)), 0.0)
        L2 = np.where(ab > 0, b * np.arcsinh(a / np.where(ab > 0, ab, 1.0)), 0.0)
        logr = np.log(np.where(r > 0, r, 1.0))
        T1 = np.where(aa > 0, a * np.arctan(b / np.where(aa > 0, a, 1.0)), 0.0) + np.where(r > 0, b * logr, 0.0)
        T2 = np.where(ab > 0, b * np.arctan(a / np.where(ab > 0, b, 1.0)), 0.0) + np.where(r > 0, a * logr, 0.0)
    return L1, L2, r, T1, T2


def _corner_difference(x, y, dx, dy):
    """[[F]] = F(x+,y+) - F(x+,y-) - F(x-,y+) + F(x-,y-) for the five primitives at once."""
    total = [0.0] * 5
    for sx, sy, sign in ((1, 1, 1.0), (1, -1, -1.0), (-1, 1, -1.0), (-1, -1, 1.0)):
        prims = _primitives(x + sx * 0.5 * dx, y + sy * 0.5 * dy)
        total = [t + sign * p for t, p in zip(total, prims)]
    return total


def _assemble(x, y, dx, dy, c: float, nu: float, ck: float) -> np.ndarray:
    """A_ij with prefactor c (normal/tangential), Poisson ratio nu and coupling prefactor ck."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    L1, L2, R, T1, T2 = _corner_difference(x, y, dx, dy)
    A = np.empty(np.broadcast(x, y).shape + (3, 3))
    A[..., X, X] = c * ((1 - nu) * L1 + L2)
    A[..., Y, Y] = c * (L1 + (1 - nu) * L2)
    A[..., Z, Z] = c * (1 - nu) * (L1 + L2)
    A[..., X, Y] = A[..., Y, X] = -c * nu * R
    A[..., Z, X] = ck * T1
    A[..., X, Z] = -ck * T1
    A[..., Z, Y] = ck * T2
    A[..., Y, Z] = -ck * T2
    return A


def rectangle_influence(x, y, dx: float, dy: float, *, G: float, nu: float, K: float = 0.0) -> np.ndarray:
    """Two-body influence numbers A_ij(x, y), shape x.shape + (3, 3) (reference §3.2).

    G, nu, K are the combined constants (:class:`~conformal.materials.Material`).
    """
    return _assemble(x, y, dx, dy, 1.0 / (math.pi * G), nu, K / (math.pi * G))


def single_body_influence(x, y, dx: float, dy: float, *, G: float, nu: float) -> np.ndarray:
    """Influence numbers of ONE half-space (body in z > 0) loaded on its surface: its own
    displacement per unit traction acting on it (Boussinesq-Cerruti, reference §3.2, last note)."""
    return _assemble(x, y, dx, dy, 1.0 / (2 * math.pi * G), nu, (1 - 2 * nu) / (4 * math.pi * G))


# ------------------------------------------------------------------ FFT operator on a grid
def _offsets(m: int, M: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets d(k) in wrap-around order for a padded length M >= 2m-1, and the mask of used k."""
    k = np.arange(M)
    d = np.where(k <= m - 1, k, k - M)
    used = (k <= m - 1) | (k >= M - m + 1)
    return d, used


@dataclass(frozen=True, eq=False)
class HalfSpaceInfluence:
    """The influence operator of a uniform mx x my grid of dx x dy elements.

    ``apply(p)`` takes tractions p of shape (3, mx, my) ordered (x, y, z) and returns the
    displacement differences u of the same shape; ``apply_normal(pn)`` and
    ``apply_tangential(px, py)`` are the cheaper products of the uncoupled sub-problems.

    >>> from conformal.materials import Material
    >>> op = HalfSpaceInfluence.for_grid(3, 2, 1.0, 1.0, Material.identical(1.0, 0.28))
    >>> D = op.dense()
    >>> bool(np.allclose(D, D.T)), D.shape
    (True, (18, 18))
    """

    mx: int
    my: int
    dx: float
    dy: float
    G: float
    nu: float
    K: float
    _fhat: dict = field(repr=False, default_factory=dict)

    @classmethod
    def for_grid(cls, mx: int, my: int, dx: float, dy: float, material: Material) -> "HalfSpaceInfluence":
        op = cls(mx, my, dx, dy, material.G, material.nu, material.K)
        Mx, My = sfft.next_fast_len(2 * mx - 1, real=True), sfft.next_fast_len(2 * my - 1, real=True)
        ox, ux = _offsets(mx, Mx)
        oy, uy = _offsets(my, My)
        A = rectangle_influence(ox[:, None] * dx, oy[None, :] * dy, dx, dy, G=op.G, nu=op.nu, K=op.K)
        A *= (ux[:, None] & uy[None, :])[..., None, None]
        for i, j in ((X, X), (Y, Y), (Z, Z), (X, Y), (Z, X), (Z, Y)):
            op._fhat[i, j] = sfft.rfft2(A[..., i, j])
        op._fhat["shape"] = (Mx, My)
        op._fhat["kernel"] = A  # wrap-around kernel, kept for dense() and self terms
        return op

    @property
    def coupled(self) -> bool:
        return abs(self.K) > 0.0

    def _kernel_hat(self, i: int, j: int) -> np.ndarray:
        if (i, j) in self._fhat:
            return self._fhat[i, j]
        if i == Y and j == X:
            return self._fhat[X, Y]
        return -self._fhat[j, i]  # A_xz = -A_zx, A_yz = -A_zy

    def _forward(self, p: np.ndarray) -> np.ndarray:
        return sfft.rfft2(p, s=self._fhat["shape"])

    def _back(self, uhat: np.ndarray) -> np.ndarray:
        return sfft.irfft2(uhat, s=self._fhat["shape"])[: self.mx, : self.my]

    def apply(self, p: np.ndarray) -> np.ndarray:
        """u = A p for tractions p of shape (3, mx, my)."""
        ph = [self._forward(p[j]) for j in range(3)]
        u = np.empty((3, self.mx, self.my))
        for i in range(3):
            acc = self._kernel_hat(i, i) * ph[i]
            for j in range(3):
                if j != i and (self.coupled or {i, j} == {X, Y}):
                    acc = acc + self._kernel_hat(i, j) * ph[j]
            u[i] = self._back(acc)
        return u

    def apply_normal(self, pn: np.ndarray) -> np.ndarray:
        """u_n due to p_n alone (the normal problem of quasi-identical bodies)."""
        return self._back(self._fhat[Z, Z] * self._forward(pn))

    def apply_tangential(self, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u_x, u_y) due to (p_x, p_y) alone."""
        hx, hy = self._forward(px), self._forward(py)
        return (self._back(self._fhat[X, X] * hx + self._fhat[X, Y] * hy),
                self._back(self._fhat[X, Y] * hx + self._fhat[Y, Y] * hy))

    def self_influence(self) -> np.ndarray:
        """A_ij(0, 0), the 3 x 3 self term (diagonal)."""
        return self._fhat["kernel"][0, 0]

    def dense(self) -> np.ndarray:
        """The full 3N x 3N matrix (N = mx my; rows/cols ordered component-major, then ix, iy).
        For tests and small grids only."""
        ix, iy = np.meshgrid(np.arange(self.mx), np.arange(self.my), indexing="ij")
        ix, iy = ix.ravel(), iy.ravel()
        Mx, My = self._fhat["shape"]
        kern = self._fhat["kernel"]
        dxi = (ix[:, None] - ix[None, :]) % Mx
        dyi = (iy[:, None] - iy[None, :]) % My
        blocks = kern[dxi, dyi]  # (N, N, 3, 3)
        N = ix.size
        return blocks.transpose(2, 0, 3, 1).reshape(3 * N, 3 * N)
