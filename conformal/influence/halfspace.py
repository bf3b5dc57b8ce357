"""Half-space influence numbers for piecewise-constant tractions on rectangles (Love 1929, Kalker 1990).

``A[..., i, j]`` is the displacement difference u_i = u_i(body 1) - u_i(body 2) at an offset (x, y)
from the centre of a dx x dy rectangle loaded by a unit uniform traction p_j on body 1.
Components are ordered (x, y, z) = (0, 1, 2), z = n pointing into body 1.  Displacements are
collocated at element centres (CONTACT's convention), which makes the grid matrix symmetric
(reciprocity A_ij(x, y) = A_ji(-x, -y)).  Closed forms: Love (1929) for the pressure, Kalker (1990, ch. 1) for the shear loads.

On a uniform grid the numbers depend only on the index offset (block Toeplitz), so products are
zero-padded FFT convolutions (DC-FFT, Liu, Wang & Liu 2000): O(N log N), no N x N matrix.

>>> import numpy as np
>>> A = rectangle_influence(np.array(0.0), np.array(0.0), 1.0, 1.0, G=1.0, nu=0.28, K=0.1)
>>> round(float(A[2, 2]), 12)    # 4 (1-nu) asinh(1) / pi, reference Table 1
0.807983787368
"""
from __future__ import annotations

import functools
import math
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy import fft as sfft

from conformal.influence import fft as ffts
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
# Parities of the corner primitives (reference §3.1) under a -> -a and b -> -b.  Corner offsets of
# a uniform grid are half-integer multiples of dx, dy (never 0), so each primitive is evaluated
# once on the positive quadrant of the corner lattice and mirrored.
_PARITY = {"L1": (-1, -1), "L2": (-1, -1), "R": (1, 1), "T1": (1, -1), "T2": (-1, 1)}
_PRIM_INDEX = {"L1": 0, "L2": 1, "R": 2, "T1": 3, "T2": 4}


def _differences(F: np.ndarray, name: str) -> np.ndarray:
    """[[F]] = F(x+,y+) - F(x+,y-) - F(x-,y+) + F(x-,y-) of one corner primitive at the offsets
    -(nx-1) .. nx-1, -(ny-1) .. ny-1 of an element, shape (2nx-1, 2ny-1), from its values F
    (nx, ny) on the positive quadrant of the corner lattice and its parities (reference §4.1).
    Elementwise: the number at an offset is the same for every nx, ny that cover it."""
    nx, ny = F.shape
    sa, sb = _PARITY[name]
    full = np.empty((2 * nx, 2 * ny))
    full[nx:, ny:] = F        # the mirrored quadrants: times +-1, i.e. copied or negated (exact)
    for rows, cols, sign in ((slice(None, nx), slice(ny, None), sa), (slice(nx, None), slice(None, ny), sb),
                             (slice(None, nx), slice(None, ny), sa * sb)):
        src = F[::-1 if rows.stop else 1, ::-1 if cols.stop else 1]
        if sign > 0:
            full[rows, cols] = src
        else:
            np.negative(src, out=full[rows, cols])
    D = np.subtract(full[1:, 1:], full[1:, :-1])      # ((F++ - F+-) - F-+) + F--, in place
    D -= full[:-1, 1:]
    D += full[:-1, :-1]
    return D


#: the influence components even (+1) or odd (-1) in both x and y (their transforms are real)
_PARITY_XY = {(Z, Z): 1, (X, X): 1, (Y, Y): 1, (X, Y): -1}


def _transform_type1(q: np.ndarray, odd: bool) -> np.ndarray:
    """The unnormalised 2-D DCT-I (``odd``: DST-I) of q: ``scipy.fft.dctn(q, type=1)`` (``dstn``),
    by pocketfft's binding where :mod:`conformal.influence.fft` calls it directly (the function
    and arguments scipy.fft passes, without its dispatch)."""
    pf = ffts._PF
    if pf is None:
        return (sfft.dstn if odd else sfft.dctn)(q, type=1)
    return (pf.dst if odd else pf.dct)(q, 1, (0, 1), 0, None, 1)


def _wrap(D: np.ndarray, mx: int, my: int, Mx: int, My: int) -> np.ndarray:
    """Place D[i, j] (offset i - (mx-1), j - (my-1)) into wrap-around order on an Mx x My array."""
    C = np.zeros((Mx, My))
    C[:mx, :my] = D[mx - 1:, my - 1:]
    C[:mx, My - my + 1:] = D[mx - 1:, :my - 1]
    C[Mx - mx + 1:, :my] = D[:mx - 1, my - 1:]
    C[Mx - mx + 1:, My - my + 1:] = D[:mx - 1, :my - 1]
    return C


@dataclass(frozen=True, eq=False)
class HalfSpaceInfluence:
    """The influence operator of a uniform mx x my grid of dx x dy elements.

    ``apply(p)`` takes tractions p of shape (3, mx, my) ordered (x, y, z) and returns the
    displacement differences u of the same shape; ``apply_normal(pn)`` and
    ``apply_tangential(px, py)`` are the cheaper products of the uncoupled sub-problems;
    ``apply_coupling_tn(pn)`` and ``apply_coupling_nt(px, py)`` the parts proportional to K.

    Kernels and their transforms are computed on first use (the normal problem of
    quasi-identical bodies needs only A_zz).  Each kernel comes from one evaluation of the
    corner primitives on the (2mx x 2my) corner lattice, of which only the positive quadrant is
    computed (parities, reference §4.1), or from the shared lattice of its element size
    (:class:`CornerLattice`); the FFT products transform only the mx non-zero rows
    along y before the transform along x (a pruned zero-padded FFT).

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
    def for_grid(cls, mx: int, my: int, dx: float, dy: float, material: Material, *,
                 shared: bool = True) -> "HalfSpaceInfluence":
        """The operator of an mx x my grid of dx x dy elements.  With ``shared`` (default), grids
        of at most CACHE_ELEMENTS elements share one operator per (shape, spacing, material) within
        the process (:func:`_shared_operator`), so its kernels and their transforms are computed
        once, and every shared operator takes its corner primitives from the lattice of its
        element size (:class:`CornerLattice`); ``shared=False`` builds a fresh one that computes
        all of it itself (timings that include the set-up)."""
        key = (int(mx), int(my), float(dx), float(dy), float(material.G), float(material.nu), float(material.K))
        if shared and cls is HalfSpaceInfluence and key[0] * key[1] <= CACHE_ELEMENTS:
            return _shared_operator(*key)
        return _padded(cls(*key), lattice=shared)

    @property
    def coupled(self) -> bool:
        return abs(self.K) > 0.0

    @property
    def padded_shape(self) -> tuple[int, int]:
        """(Mx, My), the zero-padded FFT size."""
        return self._fhat["shape"]

    # -------------------------------------------------------------- kernels (lazy)
    def _primitive_difference(self, name: str) -> np.ndarray:
        """[[F]] of one corner primitive at every grid offset, shape (2mx-1, 2my-1): for an operator
        on its element size's lattice a read-only view of the lattice's differences
        (:meth:`CornerLattice.differences`), else computed from the grid's own corners and kept."""
        if self._fhat.get("lattice"):
            return _corner_lattice(self.dx, self.dy).differences(name, self.mx, self.my)
        key = ("D", name)
        if key not in self._fhat:
            mx, my = self.mx, self.my
            if "primitives" not in self._fhat:   # all five at once (one evaluation per operator)
                cx = (np.arange(mx) + 0.5) * self.dx
                cy = (np.arange(my) + 0.5) * self.dy
                self._fhat["primitives"] = _primitives(cx[:, None], cy[None, :])
            self._fhat[key] = _differences(self._fhat["primitives"][_PRIM_INDEX[name]], name)
        return self._fhat[key]

    def _combine(self, i: int, j: int, D: Callable[[str], np.ndarray]) -> np.ndarray:
        """A_ij from the corner differences D(name) (reference §3.2): elementwise, so the numbers
        at an offset do not depend on how many offsets D covers."""
        c, ck, nu = 1.0 / (math.pi * self.G), self.K / (math.pi * self.G), self.nu
        if (i, j) == (Z, Z):
            return c * (1 - nu) * (D("L1") + D("L2"))
        if (i, j) == (X, X):
            return c * ((1 - nu) * D("L1") + D("L2"))
        if (i, j) == (Y, Y):
            return c * (D("L1") + (1 - nu) * D("L2"))
        if (i, j) in ((X, Y), (Y, X)):
            return -c * nu * D("R")
        if (i, j) == (Z, X):
            return ck * D("T1")
        if (i, j) == (Z, Y):
            return ck * D("T2")
        return -self._combine(j, i, D)    # A_xz = -A_zx, A_yz = -A_zy

    def _component(self, i: int, j: int) -> np.ndarray:
        """A_ij at every grid offset, shape (2mx-1, 2my-1), index (ix - jx + mx-1, iy - jy + my-1):
        for an operator on its element size's lattice a read-only view of the component on the
        lattice (:meth:`CornerLattice.derived`, computed once per lattice size and material, not
        kept by the operator), else computed from the grid's own corners and kept."""
        if self._fhat.get("lattice"):
            return _corner_lattice(self.dx, self.dy).derived(
                ("A", i, j, self.G, self.nu, self.K), self.mx, self.my, lambda D: self._combine(i, j, D))
        key = ("A", i, j)
        if key not in self._fhat:
            if (i, j) in ((X, Z), (Y, Z)):
                self._fhat[key] = -self._component(j, i)
            else:
                self._fhat[key] = self._combine(i, j, self._primitive_difference)
        return self._fhat[key]

    def kernel(self, i: int, j: int) -> np.ndarray:
        """A_ij in wrap-around order on the padded (Mx, My) array (reference §5, step 2)."""
        Mx, My = self.padded_shape
        return _wrap(self._component(i, j), self.mx, self.my, Mx, My)

    def _kernel_hat(self, i: int, j: int) -> np.ndarray:
        if (i, j) == (Y, X):
            i, j = X, Y
        if (i, j) in ((X, Z), (Y, Z)):
            return -self._kernel_hat(j, i)  # A_xz = -A_zx, A_yz = -A_zy
        if (i, j) not in self._fhat:
            Mx, My = self.padded_shape
            if (i, j) in _PARITY_XY and Mx % 2 == 0 and My % 2 == 0:
                self._fhat[i, j] = self._symmetric_hat(i, j)
            else:
                self._fhat[i, j] = ffts.rfft2(self.kernel(i, j))
        return self._fhat[i, j]

    def _symmetric_hat(self, i: int, j: int) -> np.ndarray:
        """The transform of :meth:`kernel` of a component even (A_zz, A_xx, A_yy) or odd (A_xy) in
        both x and y, on even padded sizes: real, and even in the wave numbers (odd for A_xy), so
        the half-spectrum comes from the (Mx/2 + 1, My/2 + 1) quarter of the kernel at offsets
        >= 0 by a 2-D DCT-I (DST-I of offsets >= 1 for A_xy, times -1: the -i of each axis'
        sine transform), mirrored to the wave numbers beyond Mx/2.  About half the transform
        work of the rfft2 of the wrapped kernel (the 176 kernel spectra of the first Manchester
        sweep, 144 of them on even sizes, with their single-precision factors: 127 M instructions
        by rfft2, 95 M so; callgrind), and no imaginary parts: the rfft2's
        are rounding noise of the kernel's asymmetry at the last bit (about 4e-16 of the largest
        value, 4e-15 for A_xy), and its real parts differ from these by as much, so the products
        differ from the rfft2's at the rounding level."""
        Mx, My = self.padded_shape
        hx, hy = Mx // 2, My // 2
        mx, my = self.mx, self.my
        A = self._component(i, j)
        re = np.empty((Mx, hy + 1))
        if _PARITY_XY[i, j] > 0:
            q = np.zeros((hx + 1, hy + 1))
            q[:mx, :my] = A[mx - 1:, my - 1:]
            re[:hx + 1] = _transform_type1(q, odd=False)
            re[hx + 1:] = re[hx - 1:0:-1]
        else:
            q = np.zeros((hx - 1, hy - 1))
            q[:mx - 1, :my - 1] = A[mx:, my:]
            re[0], re[hx] = 0.0, 0.0
            re[1:hx, 0], re[1:hx, hy] = 0.0, 0.0
            np.negative(_transform_type1(q, odd=True), out=re[1:hx, 1:hy])
            np.negative(re[hx - 1:0:-1], out=re[hx + 1:])
        re.flags.writeable = False
        self._fhat["real", i, j] = re          # (the single-precision product's factors)
        return re.astype(complex)

    def kernel_hat(self, i: int, j: int) -> np.ndarray:
        """The (Mx, My//2+1) real-to-complex transform of :meth:`kernel`."""
        return self._kernel_hat(i, j)

    def real_kernel_hat(self, i: int, j: int) -> np.ndarray | None:
        """:meth:`kernel_hat` as a real array where it is real: the one :meth:`_symmetric_hat`
        computed, else the real part of the rfft2's where its imaginary part is rounding (at most
        1e-9 of its largest value), else None.  The factors of the single-precision products."""
        hat = self._kernel_hat(i, j)
        re = self._fhat.get(("real", i, j))
        if re is not None:
            return re
        return hat.real if ffts.imag_negligible(hat, 1e-9) else None

    # -------------------------------------------------------------- products
    def _forward(self, p: np.ndarray) -> np.ndarray:
        """Zero-padded rfft2 of p (..., mx, my): only the mx non-zero rows are transformed along y,
        straight into the first mx rows of the padded half-spectrum (:mod:`conformal.influence.fft`)."""
        Mx, My = self.padded_shape
        spec = np.zeros(p.shape[:-2] + (Mx, My // 2 + 1), dtype=complex)
        ffts.rfft(p, My, axis=-1, out=spec[..., : self.mx, :])
        return ffts.fft(spec, axis=-2, overwrite=True)

    def _back(self, uhat: np.ndarray) -> np.ndarray:
        """irfft2 restricted to the first mx x my entries (only mx rows are transformed back along
        y); overwrites ``uhat``."""
        Mx, My = self.padded_shape
        cols = ffts.ifft(uhat, axis=-2, overwrite=True)[..., : self.mx, :]
        return ffts.irfft(cols, My, axis=-1)[..., : self.my]

    def apply(self, p: np.ndarray) -> np.ndarray:
        """u = A p for tractions p of shape (3, mx, my)."""
        ph = self._forward(np.asarray(p, dtype=float))
        acc = np.empty_like(ph)
        for i in range(3):
            acc[i] = self._kernel_hat(i, i) * ph[i]
            for j in range(3):
                if j != i and (self.coupled or {i, j} == {X, Y}):
                    acc[i] += self._kernel_hat(i, j) * ph[j]
        return self._back(acc)

    def apply_normal(self, pn: np.ndarray) -> np.ndarray:
        """u_n due to p_n alone (the normal problem of quasi-identical bodies)."""
        pn = np.asarray(pn, dtype=float)
        if pn.ndim == 2:    # one field: the same transforms in one call (bitwise the numbers below)
            return ffts.padded_product(pn, self._kernel_hat(Z, Z), self._fhat["shape"])
        uh = self._forward(pn)
        uh *= self._kernel_hat(Z, Z)
        return self._back(uh)

    def apply_tangential(self, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u_x, u_y) due to (p_x, p_y) alone."""
        # both fields zero-padded along y in one array (the rows :func:`_forward` transforms), and
        # the kernel products into their result (the numbers of the stacked fields and of
        # fxx h0 + fxy h1, fxy h0 + fyy h1)
        Mx, My = self.padded_shape
        rows = np.zeros((2, self.mx, My))
        rows[0, :, :self.my] = px
        rows[1, :, :self.my] = py
        h = self._forward(rows)
        fxx, fxy, fyy = self._kernel_hat(X, X), self._kernel_hat(X, Y), self._kernel_hat(Y, Y)
        acc = np.empty_like(h)
        np.multiply(fxx, h[0], out=acc[0])
        acc[0] += fxy * h[1]
        np.multiply(fxy, h[0], out=acc[1])
        acc[1] += fyy * h[1]
        u = self._back(acc)
        return u[0], u[1]

    def apply_coupling_nt(self, px: np.ndarray, py: np.ndarray) -> np.ndarray:
        """u_n due to (p_x, p_y): A_zx p_x + A_zy p_y (zero for quasi-identical bodies)."""
        if not self.coupled:
            return np.zeros((self.mx, self.my))
        h = self._forward(np.stack([np.asarray(px, dtype=float), np.asarray(py, dtype=float)]))
        return self._back(self._kernel_hat(Z, X) * h[0] + self._kernel_hat(Z, Y) * h[1])

    def apply_coupling_tn(self, pn: np.ndarray) -> np.ndarray:
        """(u_x, u_y) due to p_n, shape (2, mx, my): A_xz p_n, A_yz p_n (zero when K = 0)."""
        if not self.coupled:
            return np.zeros((2, self.mx, self.my))
        h = self._forward(np.asarray(pn, dtype=float))
        return self._back(np.stack([self._kernel_hat(X, Z) * h, self._kernel_hat(Y, Z) * h]))

    def self_influence(self) -> np.ndarray:
        """A_ij(0, 0), the 3 x 3 self term (diagonal)."""
        if "self" not in self._fhat:        # (kept: a lattice operator's components are views, not kept)
            S = np.zeros((3, 3))
            for i in range(3):
                S[i, i] = self._component(i, i)[self.mx - 1, self.my - 1]
            self._fhat["self"] = S
        return self._fhat["self"].copy()

    # -------------------------------------------------------------- the operator protocol
    def contact_modulus(self) -> float:
        """E* = G / (1 - nu) of the combined constants (N/mm²)."""
        return self.G / (1.0 - self.nu)

    def normal_preconditioner(self) -> Callable[[np.ndarray], np.ndarray]:
        """z = P g, an approximate inverse of A_zz by FFT (after CONTACT's NormCG).

        The half-space maps a pressure wave of wave number k to a displacement 2(1-nu)/(G |k|) times
        it (Boussinesq), so P multiplies by |k| (the constant does not matter to CG).  The discrete
        wave numbers 2 sin(k dx/2)/dx keep P positive definite.  (The inverse of the circulant
        embedding of the discrete kernel is better for square elements but indefinite for
        dx != dy: measured 146 to >1000 iterations at dx/dy = 0.3, against 13-16 with this P.)

        P acts on the periodic grid of Nx x Ny >= mx x my elements (the next fast FFT lengths), not on
        the zero-padded grid of the products: it only has to approximate the inverse on the contact
        set, and a quarter of the transform size was measured to give the same iteration counts
        (the 69 normal solves of the Manchester A-2.2 sequence: 662 iterations either way; Hertz
        circles of 30² to 200² elements, 6-7 each; an ellipse of axis ratio 8, 11 instead of 10),
        at 0.57 of the time of a cold 200 x 200 solve.
        """
        if "pc_periodic" not in self._fhat:
            Nx, Ny = sfft.next_fast_len(self.mx, real=True), sfft.next_fast_len(self.my, real=True)
            kx = 2.0 * np.sin(np.pi * np.fft.fftfreq(Nx))[:, None] / self.dx
            ky = 2.0 * np.sin(np.pi * np.fft.rfftfreq(Ny))[None, :] / self.dy
            sym = np.hypot(kx, ky)
            # every wave number but (0, 0) is positive (sin(pi f) != 0 for the frequencies f != 0
            # of fftfreq), so the smallest positive one is the smallest after the first
            rest = sym.ravel()[1:]
            sym[0, 0] = rest.min() if rest.size else 1.0
            self._fhat["pc_periodic"] = (Nx, Ny, sym)
        Nx, Ny, sym = self._fhat["pc_periodic"]
        mx, my = self.mx, self.my
        # the periodic grid's field, zero beyond the mx x my elements: one per preconditioner (a
        # solve), written anew by each call (its zeros stay)
        pad = np.zeros((Nx, Ny)) if (Nx, Ny) != (mx, my) else None

        def apply(g: np.ndarray) -> np.ndarray:
            if pad is not None:
                x = pad
                x[:mx, :my] = g
            else:
                x = g
            gh = ffts.rfft2(x)
            gh *= sym
            return ffts.irfft2(gh, (Nx, Ny))[:mx, :my]

        return apply

    def normal_product32(self) -> Callable[[np.ndarray], np.ndarray] | None:
        """u_n = A_zz p_n in single precision (:func:`conformal.influence.fft.padded_product32`,
        relative error about 3e-7 on the patch grids of a wheel-rail sweep), float64 in and out,
        for the iterations of the normal problem far from their tolerance
        (:mod:`conformal.solvers.normal`); built once per operator.  A_zz is even in x and y, so its
        transform is real (:meth:`real_kernel_hat`; None where it is not)."""
        if "normal32" not in self._fhat:
            re = self.real_kernel_hat(Z, Z)
            self._fhat["normal32"] = None if re is None else ffts.doubled(re.astype(np.float32))
        k2, shape = self._fhat["normal32"], self._fhat["shape"]
        if k2 is None:
            return None

        def apply(pn: np.ndarray) -> np.ndarray:
            return ffts.padded_product32(pn.astype(np.float32), k2, shape).astype(np.float64)

        return apply

    def tangential_product32(self) -> Callable[[np.ndarray], np.ndarray]:
        """(u_x, u_y) = A_tt p in single precision (:class:`TangentialProduct32`), built once per
        operator (it holds only the operator's transforms)."""
        if "product32" not in self._fhat:
            self._fhat["product32"] = TangentialProduct32(self)
        return self._fhat["product32"]

    def extended(self, ncols: int) -> "HalfSpaceInfluence":
        """The same numbers on a grid ``ncols`` elements longer in x (downstream)."""
        return self._on_grid(self.mx + int(ncols), self.my, self.dx, self.dy)

    def coarsened(self, fx: int, fy: int) -> "HalfSpaceInfluence":
        """The operator of the grid of fx x fy merged elements (ceil(mx/fx) x ceil(my/fy) elements
        of fx dx x fy dy), e.g. for a nested start or a coarse-grid correction."""
        fx, fy = int(fx), int(fy)
        return self._on_grid(-(-self.mx // fx), -(-self.my // fy), fx * self.dx, fy * self.dy)

    def window(self, mx: int, my: int) -> "HalfSpaceInfluence":
        """The operator of a window of mx x my elements of this grid: the half-space is invariant to
        translations, so it is the operator of an mx x my grid of the same spacing, shared per
        shape (``_window_operator``, apart from the operators of whole grids)."""
        mx, my = int(mx), int(my)
        if mx * my > CACHE_ELEMENTS:
            return self._on_grid(mx, my, self.dx, self.dy)
        return _window_operator(mx, my, float(self.dx), float(self.dy), float(self.G), float(self.nu), float(self.K))

    def _on_grid(self, mx: int, my: int, dx: float, dy: float) -> "HalfSpaceInfluence":
        """The operator of the same constants on another uniform grid."""
        return _padded(HalfSpaceInfluence(mx, my, dx, dy, self.G, self.nu, self.K), lattice=True)

    def dense(self) -> np.ndarray:
        """The full 3N x 3N matrix (N = mx my; rows/cols ordered component-major, then ix, iy).
        For tests and small grids only."""
        ix, iy = np.meshgrid(np.arange(self.mx), np.arange(self.my), indexing="ij")
        ix, iy = ix.ravel(), iy.ravel()
        dxi = ix[:, None] - ix[None, :] + self.mx - 1
        dyi = iy[:, None] - iy[None, :] + self.my - 1
        N = ix.size
        out = np.empty((3 * N, 3 * N))
        for i in range(3):
            for j in range(3):
                out[i * N:(i + 1) * N, j * N:(j + 1) * N] = self._component(i, j)[dxi, dyi]
        return out


#: operators of grids up to this many elements are shared (:func:`_shared_operator`); the kernels
#: and transforms of a 200 x 200 grid take about 15 MB
CACHE_ELEMENTS = 40000
#: ... and the least recently used are dropped when the grids of those kept exceed the elements
#: of this many of the largest (CACHE_TOTAL_ELEMENTS, the memory of 8 operators of 200 x 200; the
#: 35 grids of a 21-position Manchester sweep at 0.2 mm, 70 000 elements, all stay, so a second
#: sweep computes no kernel) ...
CACHE_SIZE = 8
CACHE_TOTAL_ELEMENTS = CACHE_SIZE * CACHE_ELEMENTS
#: ... or when more than this many operators are kept
CACHE_OPERATORS = 64


class _OperatorCache:
    """The shared operators by (mx, my, dx, dy, G, nu, K), least recently used first, bounded by
    the number of operators and the elements of their grids in all."""

    def __init__(self, max_entries: int, max_elements: int):
        self.max_entries, self.max_elements = max_entries, max_elements
        self._ops: OrderedDict[tuple, HalfSpaceInfluence] = OrderedDict()
        self._elements = 0

    def __call__(self, mx: int, my: int, dx: float, dy: float, G: float, nu: float, K: float) -> HalfSpaceInfluence:
        key = (mx, my, dx, dy, G, nu, K)
        op = self._ops.get(key)
        if op is not None:
            self._ops.move_to_end(key)
            return op
        op = _padded(HalfSpaceInfluence(mx, my, dx, dy, G, nu, K), lattice=True)
        self._ops[key] = op
        self._elements += mx * my
        while len(self._ops) > 1 and (len(self._ops) > self.max_entries or self._elements > self.max_elements):
            (ox, oy, *_), _ = self._ops.popitem(last=False)
            self._elements -= ox * oy
        return op

    def __len__(self) -> int:
        return len(self._ops)

    @property
    def elements(self) -> int:
        """The grid elements of the operators kept."""
        return self._elements

    def cache_clear(self) -> None:
        self._ops.clear()
        self._elements = 0


#: One operator per grid and material within the process: a sweep solves the normal and the
#: contact problems of a position (and often of its neighbours) on grids of equal shape and
#: spacing, and the lazily computed kernels, their transforms, the normal preconditioner's
#: symbol and the single-precision tangential product are then computed once.  The entries are
#: pure functions of the arguments, so sharing gives the numbers of a fresh operator.
_shared_operator = _OperatorCache(CACHE_OPERATORS, CACHE_TOTAL_ELEMENTS)


#: The operators of windows (:meth:`HalfSpaceInfluence.window`), shared like the operators of whole
#: grids but kept apart from them, so that the windows of the contact solves of a sweep (a few
#: shapes: their sides are rounded) do not push the operators of its grids out.
_window_operator = _OperatorCache(2 * CACHE_SIZE, CACHE_TOTAL_ELEMENTS)


def _padded(op: HalfSpaceInfluence, *, lattice: bool = False) -> HalfSpaceInfluence:
    """Record the zero-padded FFT size (Mx, My) >= (2mx-1, 2my-1) of a new operator, and whether it
    takes its corner primitives from the shared lattice of its element size."""
    op._fhat["shape"] = (sfft.next_fast_len(2 * op.mx - 1, real=True), sfft.next_fast_len(2 * op.my - 1, real=True))
    op._fhat["lattice"] = bool(lattice and op.mx * op.my <= CACHE_ELEMENTS)
    return op


class CornerLattice:
    """The five corner primitives (:func:`_primitives`) at the corners ((i + 1/2) dx, (j + 1/2) dy),
    i < nx, j < ny, of one element size: the positive quadrant of the corner lattice of every
    grid of that size up to nx x ny elements (reference §4.1).  A grid of mx x my elements takes
    the slice [:mx, :my], bitwise the values its own evaluation gives (each value is computed
    elementwise from its own corner); the lattice grows by the corners a larger grid adds, so a
    sweep over some 35 grid shapes evaluates the primitives at the corners of the largest only
    (a fifth of the evaluations of one per grid).  The lattice also keeps the corner differences
    [[F]] at all its offsets (:meth:`differences`) and what is computed from them elementwise (the
    influence components of a material, :meth:`derived`): a grid's are the slice around the
    centre, so a new grid shape costs only the wrap-around and the FFT of its kernels.

    >>> lat = CornerLattice(0.2, 0.2)
    >>> F = lat.primitives(3, 2); G = lat.primitives(5, 4)
    >>> lat.shape, bool(np.array_equal(F[0], G[0][:3, :2]))
    ((5, 4), True)
    """

    def __init__(self, dx: float, dy: float, max_elements: int = 2 * 40000):
        self.dx, self.dy = float(dx), float(dy)
        self.max_elements = int(max_elements)
        self._F: tuple[np.ndarray, ...] | None = None
        self._D: dict[str, np.ndarray] = {}
        self._derived: OrderedDict[tuple, np.ndarray] = OrderedDict()
        self.shape = (0, 0)

    def _corners(self, i0: int, i1: int, j0: int, j1: int) -> tuple[np.ndarray, ...]:
        cx = (np.arange(i1) + 0.5) * self.dx
        cy = (np.arange(j1) + 0.5) * self.dy
        return _primitives(cx[i0:, None], cy[None, j0:])

    def primitives(self, mx: int, my: int) -> tuple[np.ndarray, ...]:
        """L1, L2, R, T1, T2 at the corners of an mx x my grid, each (mx, my) (read-only views)."""
        nx, ny = self.shape
        if mx > nx or my > ny:
            gx, gy = max(mx, nx), max(my, ny)
            # a side that grows grows by half at least (the growing shapes of a sweep: fewer growths,
            # each of which computes the lattice's differences anew), within the bound
            wx = max(gx, nx + nx // 2) if mx > nx and nx else gx
            wy = max(gy, ny + ny // 2) if my > ny and ny else gy
            if wx * wy <= self.max_elements:
                gx, gy = wx, wy
            elif gx * gy > self.max_elements:     # shapes far apart (a long and a wide grid): start anew
                self._F, (nx, ny), (gx, gy) = None, (0, 0), (mx, my)
            if self._F is None:
                F = self._corners(0, gx, 0, gy)
            else:   # the corners the larger lattice adds: the rows below, the columns right of the old
                below = self._corners(nx, gx, 0, gy)
                right = self._corners(0, nx, ny, gy)
                F = tuple(np.concatenate([np.concatenate([old, r], axis=1), b], axis=0)
                          for old, r, b in zip(self._F, right, below))
            for a in F:
                a.flags.writeable = False
            self._F, self.shape = F, (gx, gy)
            self._D, self._derived = {}, OrderedDict()
        return tuple(a[:mx, :my] for a in self._F)

    def _lattice_difference(self, name: str) -> np.ndarray:
        """[[F]] of the primitive ``name`` at every offset of the lattice, (2nx-1, 2ny-1)."""
        D = self._D.get(name)
        if D is None:
            D = _differences(self._F[_PRIM_INDEX[name]], name)
            D.flags.writeable = False
            self._D[name] = D
        return D

    def _centre(self, A: np.ndarray, mx: int, my: int) -> np.ndarray:
        nx, ny = self.shape
        return A[nx - mx:nx + mx - 1, ny - my:ny + my - 1]

    def differences(self, name: str, mx: int, my: int) -> np.ndarray:
        """[[F]] of the primitive ``name`` at the offsets of an mx x my grid, (2mx-1, 2my-1)
        (a read-only view): the slice around the centre of the differences at every offset of
        the lattice, computed once per lattice size; bitwise the grid's own
        (:func:`_differences` is elementwise on the same corner values)."""
        self.primitives(mx, my)
        return self._centre(self._lattice_difference(name), mx, my)

    def derived(self, key: tuple, mx: int, my: int,
                compute: Callable[[Callable[[str], np.ndarray]], np.ndarray]) -> np.ndarray:
        """An elementwise function of the corner differences (e.g. an influence component of one
        material) at the offsets of an mx x my grid, (2mx-1, 2my-1) (a read-only view):
        ``compute(D)`` with ``D(name)`` the differences at every offset of the lattice, evaluated
        once per lattice size and ``key`` (the :data:`LATTICE_DERIVED` latest keys kept), sliced
        per grid; bitwise the function of the grid's own differences."""
        self.primitives(mx, my)
        A = self._derived.get(key)
        if A is None:
            A = compute(self._lattice_difference)
            A.flags.writeable = False
            self._derived[key] = A
            while len(self._derived) > LATTICE_DERIVED:
                self._derived.popitem(last=False)
        else:
            self._derived.move_to_end(key)
        return self._centre(A, mx, my)


#: the arrays derived from a corner lattice's differences that it keeps (:meth:`CornerLattice.derived`:
#: the influence components of a material, 4 of them for the uncoupled problems of a sweep)
LATTICE_DERIVED = 8


@functools.lru_cache(maxsize=4)
def _corner_lattice(dx: float, dy: float) -> CornerLattice:
    """The corner lattice of one element size, shared within the process by the grids of at most
    CACHE_ELEMENTS elements (at most 2 CACHE_ELEMENTS corners per primitive, 3.2 MB; the
    differences and derived components at its offsets, four times as many numbers each: 0.35 MB
    each for the 109 x 102 lattice of the Manchester sweep at 0.2 mm, at most 2.6 MB each)."""
    return CornerLattice(dx, dy, 2 * CACHE_ELEMENTS)


class TangentialProduct32:
    """(u_x, u_y) = A_tt p by the zero-padded FFTs of :class:`HalfSpaceInfluence`, in single
    precision (2.5x faster at 200 x 200; relative error about 1e-7), for Krylov products.  Only the
    mx non-zero rows are transformed along y, and only mx rows are transformed back.

    On large grids (the padded half-spectrum of both components above :data:`BLOCK_FROM_BYTES`)
    the transforms along x, the product with the kernels and the transforms back run on blocks of
    :data:`BLOCK_COLUMNS` columns of the half-spectrum, so that each block stays in the core's
    cache between the three passes instead of streaming the whole spectrum through memory three
    times: the same numbers (the transforms along x are per column), 14 % faster at 400 x 400
    (800 x 800 padded) and 25 % at 500 x 500 on a 2-core machine with a 512 KiB L2 cache per core,
    slower at 300 x 300 and below (the measurements at :data:`BLOCK_FROM_BYTES`).  Unblocked, one
    product grew as N^1.24 from 200² to 400² on that machine (the cache), blocked as N^1.13."""

    def __init__(self, op: HalfSpaceInfluence):
        self.mx, self.my = op.mx, op.my
        self.Mx, self.My = op.padded_shape
        pairs = ((X, X), (X, Y), (Y, Y))
        # the half-space kernels are even-even (xx, yy) or odd-odd (xy): real transforms, and a
        # real factor halves the cost of the products in Fourier space
        re = [op.real_kernel_hat(i, j) for i, j in pairs]
        real = all(r is not None for r in re)
        self.k = [r.astype(np.float32) for r in re] if real else \
            [op.kernel_hat(i, j).astype(np.complex64) for i, j in pairs]
        half = self.My // 2 + 1
        self.block = BLOCK_COLUMNS if 2 * self.Mx * half * 8 > BLOCK_FROM_BYTES else half
        # unblocked, real kernels: each value repeated for the real and imaginary part, so that the
        # products run on float32 views of the spectrum (the numbers of the complex product, without
        # numpy's mixed-type casting loop: 2-2.5x faster)
        self._k2 = [ffts.doubled(v) for v in self.k] if real and self.block >= half else None

    def __call__(self, p: np.ndarray) -> np.ndarray:
        """p: (2, mx, my) float32 (or castable); returns (2, mx, my) float32."""
        ctype = np.complex64 if p.dtype == np.float32 else np.complex128
        half = self.My // 2 + 1
        if self.block >= half:   # the row transforms straight into the padded half-spectrum
            h = np.zeros((2, self.Mx, half), dtype=ctype)
            ffts.rfft(p, self.My, axis=-1, out=h[:, : self.mx])
            return ffts.irfft(self._spectral(h, slice(None)), self.My, axis=-1)[:, :, : self.my]
        rows = ffts.rfft(p, self.My, axis=-1)
        out = np.empty_like(rows)
        h = np.zeros((2, self.Mx, self.block), dtype=ctype)
        for j0 in range(0, half, self.block):
            cols = slice(j0, min(half, j0 + self.block))
            nc = cols.stop - j0
            hb = h[:, :, :nc]
            hb[:, : self.mx] = rows[:, :, cols]
            hb[:, self.mx:] = 0.0
            out[:, :, cols] = self._spectral(hb, cols)
        return ffts.irfft(out, self.My, axis=-1)[:, :, : self.my]

    def _spectral(self, h: np.ndarray, cols: slice) -> np.ndarray:
        """The transform along x of ``h`` (2, Mx, nc): the row transforms of the half-spectrum's
        columns ``cols`` in its first mx rows, zero below; the product with the kernels there
        and the transform back, in place; returns the first mx rows (2, mx, nc)."""
        h = ffts.fft(h, axis=-2, overwrite=True)
        if self._k2 is not None and h.dtype == np.complex64 and h.flags.c_contiguous \
                and h.shape[-1] == self._k2[0].shape[-1] // 2:
            f = h.view(np.float32)
            kxx, kxy, kyy = self._k2
        else:
            f = h
            kxx, kxy, kyy = (k[:, cols] for k in self.k)
        a0 = kxx * f[0]
        a0 += kxy * f[1]
        f[1] *= kyy
        f[1] += kxy * f[0]
        f[0] = a0
        return ffts.ifft(h, axis=-2, overwrite=True)[:, : self.mx]


#: the single-precision tangential product works on column blocks of the half-spectrum
#: (:class:`TangentialProduct32`) when both components' padded half-spectrum (complex64) exceed
#: this many bytes (grids of 300 x 300, padded 600 x 600: 2.9 MB, unblocked; 400 x 400, padded
#: 800 x 800: 5.1 MB, blocked).  Measured (best of 15, single product, loaded 2-core machine): blocks
#: of 64 columns take 1.14 / 0.86 / 0.75 of the unblocked time at 300² / 400² / 500² (32: 1.19 /
#: 0.85 / 0.76; 128: 1.09 / 0.86 / 0.78) ...
BLOCK_FROM_BYTES = 4 * 2**20
#: ... of this many columns (a block of 800 padded rows: 0.8 MB for both components)
BLOCK_COLUMNS = 64
