"""Influence numbers on a curved potential contact grid, invariant along the rolling direction.

The rail is an extrusion and the wheel (nearly) a body of revolution, so along the rolling
direction x the influence numbers depend only on the offset ix - jx (a rail is an extrusion, a wheel a body of revolution).  They are
stored as a kernel ``K[kx, I, J, i, j]`` of shape (2 mx - 1, ms, ms, 3, 3):

    u_i(ix, I) = sum_jx sum_J sum_j K[ix - jx, I, J, i, j] p_j(jx, J)

where I, J are element indices along the arc length s, kx = ix - jx in -(mx-1) .. mx-1 (stored at
position kx + mx - 1), and the components (0, 1, 2) are (x, s, n) in the LOCAL frame of each
element (x rolling, s tangent along the profile, n the inner normal of body 1).  Tractions act
on body 1; u is the displacement difference body 1 - body 2, as in conformal.influence.halfspace.

Products use a zero-padded FFT along x and dense (3 ms x 3 ms) blocks per frequency.

The half-space twin, :func:`curved_halfspace_kernel`, flattens the strip (offset x, s_I - s_J)
and rotates between the element frames by the difference of contact angles, split half on each
side so that reciprocity (a symmetric matrix) is kept: u_I = R(a/2) A R(a/2) p_J with
a = delta_J - delta_I (the frame of element I is R(delta_I) applied to the side frame's; Blanco-Lorenzo's
variant 4, conformal.influence.blanco).  On a flat strip it equals the planar
half-space numbers exactly.

>>> import numpy as np
>>> from conformal.materials import Material
>>> s = np.arange(4) * 0.5 + 0.25
>>> K = curved_halfspace_kernel(3, 0.4, s, np.full(4, 0.5), np.zeros(4), Material.steel())
>>> K.shape
(5, 4, 4, 3, 3)
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import fft as sfft

from conformal.influence.halfspace import rectangle_influence
from conformal.materials import Material


def curved_halfspace_kernel(mx: int, dx: float, s_centres: np.ndarray, s_widths: np.ndarray,
                            delta: np.ndarray, material: Material, *, angle_correction: bool = True
                            ) -> np.ndarray:
    """Half-space influence kernel (2mx-1, ms, ms, 3, 3) of a curved strip grid.

    Parameters
    ----------
    mx, dx : number and length (mm) of the elements along the rolling direction.
    s_centres, s_widths : arc-length centres and widths (mm) of the ms elements along the profile.
    delta : contact angle (rad) of each element along s.
    angle_correction : rotate between element frames by delta_J - delta_I (split symmetrically).
    """
    s_centres, s_widths, delta = (np.asarray(v, dtype=float) for v in (s_centres, s_widths, delta))
    ms = s_centres.size
    kx = np.arange(-(mx - 1), mx)[:, None, None] * dx
    w0 = float(s_widths[0])
    uniform = np.allclose(s_widths, w0, rtol=1e-12, atol=0) and np.allclose(np.diff(s_centres), w0, rtol=1e-9, atol=0)
    if ms > 1 and uniform:
        # uniform strip: the numbers depend on the offset I - J only (Toeplitz along s too)
        offs = np.arange(-(ms - 1), ms) * w0
        T = rectangle_influence(kx[:, :, 0] + 0 * offs[None, :], offs[None, :] + 0 * kx[:, :, 0], dx, w0,
                                G=material.G, nu=material.nu, K=material.K)   # (2mx-1, 2ms-1, 3, 3)
        I = np.arange(ms)
        K = T[:, I[:, None] - I[None, :] + ms - 1]
    else:
        ds = (s_centres[:, None] - s_centres[None, :])[None, :, :]
        K = np.empty((2 * mx - 1, ms, ms, 3, 3))
        for J in range(ms):  # the loaded element's width differs per J on a non-uniform grid
            K[:, :, J] = rectangle_influence(kx[:, :, 0] + 0 * ds[:, :, J], ds[:, :, J] + 0 * kx[:, :, 0],
                                             dx, float(s_widths[J]), G=material.G, nu=material.nu, K=material.K)
    if angle_correction and np.ptp(delta) > 0:
        # element I's frame is the side frame turned by R(delta_I) (s = (cos, sin), n = (-sin, cos) of
        # delta in (y, z)); with the half-space numbers in the frame of the mean angle,
        # u_I = R((delta_J - delta_I) / 2) A R((delta_J - delta_I) / 2) p_J (Blanco-Lorenzo's split
        # form, CONTACT's C3 = 4 variant 4; its coupling sign agrees with the FE bodies, docs/incoming/frames21.md)
        K = _rotate_pairs(K, 0.5 * (delta[None, :] - delta[:, None]))
    return K


def _rotate_pairs(K: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """R(angle_IJ) K[k, I, J] R(angle_IJ) for rotations about x (the half-angle correction of
    :func:`curved_halfspace_kernel`), written out on the (s, n) components: the same as
    einsum("IJab,kIJbc,IJcd->kIJad", R, K, R) at a fraction of its cost."""
    c, s = np.cos(angle), np.sin(angle)
    Kc = np.ascontiguousarray(K.transpose(3, 4, 0, 1, 2))     # component-major: fast elementwise work
    M = Kc.copy()                                  # M = K R: columns 1, 2 mix
    M[:, 1] = c * Kc[:, 1] + s * Kc[:, 2]
    M[:, 2] = -s * Kc[:, 1] + c * Kc[:, 2]
    out = M.copy()                                 # R M: rows 1, 2 mix
    out[1] = c * M[1] - s * M[2]
    out[2] = s * M[1] + c * M[2]
    return np.ascontiguousarray(out.transpose(2, 3, 4, 0, 1))


@dataclass(frozen=True, eq=False)
class CurvedInfluence:
    """The influence operator of an mx x ms curved strip grid from an x-invariant kernel.

    The operator protocol of :mod:`conformal.influence.operator` (as
    :class:`~conformal.influence.halfspace.HalfSpaceInfluence`): ``apply(p)`` with p of shape
    (3, mx, ms), ``apply_normal(pn)``, ``apply_tangential(px, ps)``, ``dense()``; no
    preconditioner, extension or coarsening of its own (those return None).

    >>> from conformal.materials import Material
    >>> s = np.arange(3) * 0.5
    >>> K = curved_halfspace_kernel(4, 0.5, s, np.full(3, 0.5), np.zeros(3), Material.steel())
    >>> op = CurvedInfluence.from_kernel(K)
    >>> D = op.dense()
    >>> bool(np.allclose(D, D.T, rtol=0, atol=1e-14 * abs(D).max())), D.shape
    (True, (36, 36))
    """

    mx: int
    ms: int
    kernel: np.ndarray
    _fhat: dict = field(repr=False, default_factory=dict)

    @classmethod
    def from_kernel(cls, kernel: np.ndarray) -> "CurvedInfluence":
        kernel = np.asarray(kernel, dtype=float)
        nk, ms, ms2, three, three2 = kernel.shape
        if nk % 2 != 1 or ms != ms2 or three != 3 or three2 != 3:
            raise ValueError(f"kernel must have shape (2mx-1, ms, ms, 3, 3), got {kernel.shape}")
        mx = (nk + 1) // 2
        op = cls(mx, ms, kernel)
        M = sfft.next_fast_len(2 * mx - 1, real=True)
        wrap = np.zeros((M, ms, ms, 3, 3))
        wrap[:mx] = kernel[mx - 1:]            # offsets 0 .. mx-1
        if mx > 1:
            wrap[M - mx + 1:] = kernel[: mx - 1]  # offsets -(mx-1) .. -1
        # per frequency a dense (3 ms x 3 ms) block, rows (i, I), columns (j, J)
        fk = sfft.rfft(wrap, axis=0)                       # (F, ms, ms, 3, 3)
        op._fhat["full"] = fk.transpose(0, 3, 1, 4, 2).reshape(fk.shape[0], 3 * ms, 3 * ms)
        op._fhat["nn"] = fk[..., 2, 2]
        op._fhat["tt"] = fk[..., :2, :2].transpose(0, 3, 1, 4, 2).reshape(fk.shape[0], 2 * ms, 2 * ms)
        op._fhat["nt"] = fk[..., 2:, :2].transpose(0, 3, 1, 4, 2).reshape(fk.shape[0], ms, 2 * ms)
        op._fhat["tn"] = fk[..., :2, 2:].transpose(0, 3, 1, 4, 2).reshape(fk.shape[0], 2 * ms, ms)
        op._fhat["M"] = M
        op._fhat["coupled"] = bool(np.any(kernel[..., 2, :2] != 0.0) or np.any(kernel[..., :2, 2] != 0.0))
        return op

    @property
    def my(self) -> int:  # planar-operator name for the second grid axis
        return self.ms

    def _convolve(self, blocks: np.ndarray, p: np.ndarray) -> np.ndarray:
        """p: (c, mx, ms) -> u: (c', mx, ms) with per-frequency dense blocks (F, c' ms, c ms)."""
        M = self._fhat["M"]
        c = p.shape[0]
        ph = sfft.rfft(p, n=M, axis=1)                            # (c, F, ms)
        ph = ph.transpose(1, 0, 2).reshape(ph.shape[1], c * self.ms)  # (F, c ms)
        uh = np.einsum("fab,fb->fa", blocks, ph)
        cout = blocks.shape[1] // self.ms
        uh = uh.reshape(-1, cout, self.ms).transpose(1, 0, 2)      # (c', F, ms)
        return sfft.irfft(uh, n=M, axis=1)[:, : self.mx, :]

    def apply(self, p: np.ndarray) -> np.ndarray:
        """u = A p for tractions p of shape (3, mx, ms) in the local element frames."""
        return self._convolve(self._fhat["full"], np.asarray(p, dtype=float))

    def apply_normal(self, pn: np.ndarray) -> np.ndarray:
        return self._convolve(self._fhat["nn"], np.asarray(pn, dtype=float)[None])[0]

    def apply_tangential(self, px: np.ndarray, ps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = self._convolve(self._fhat["tt"], np.stack([px, ps]).astype(float))
        return u[0], u[1]

    @property
    def coupled(self) -> bool:
        """True where normal and tangential components interact (A_nt != 0): dissimilar materials,
        contact angles that vary across the strip, or FE numbers of curved bodies."""
        return self._fhat["coupled"]

    def apply_coupling_nt(self, px: np.ndarray, ps: np.ndarray) -> np.ndarray:
        """u_n due to (p_x, p_s): A_nx p_x + A_ns p_s."""
        if not self.coupled:
            return np.zeros((self.mx, self.ms))
        return self._convolve(self._fhat["nt"], np.stack([px, ps]).astype(float))[0]

    def apply_coupling_tn(self, pn: np.ndarray) -> np.ndarray:
        """(u_x, u_s) due to p_n, shape (2, mx, ms): A_xn p_n, A_sn p_n."""
        if not self.coupled:
            return np.zeros((2, self.mx, self.ms))
        return self._convolve(self._fhat["tn"], np.asarray(pn, dtype=float)[None])

    # -------------------------------------------------------------- the operator protocol
    def contact_modulus(self) -> float | None:
        """None: a strip kernel carries no single pair of elastic constants."""
        return None

    def normal_preconditioner(self) -> None:
        """None: no cheap approximate inverse of A_nn is known for a general strip kernel."""
        return None

    def tangential_product32(self) -> None:
        """None: the strip products stay in double precision."""
        return None

    def extended(self, ncols: int) -> None:
        """None: the kernel holds offsets up to mx - 1 only (a longer grid needs new numbers)."""
        return None

    def coarsened(self, fx: int, fy: int) -> None:
        """None: coarser strips need new numbers (e.g. new FE influence numbers)."""
        return None

    def window(self, mx: int, my: int) -> None:
        """None: the strip kernel depends on the position across the strip."""
        return None

    def self_influence(self) -> np.ndarray:
        """Self terms A_ii of each element along s, shape (ms, 3, 3)."""
        k0 = self.kernel[self.mx - 1]
        return k0[np.arange(self.ms), np.arange(self.ms)]

    def dense(self) -> np.ndarray:
        """Full 3N x 3N matrix, N = mx ms, ordered component-major then (ix, I) (tests only)."""
        ix = np.repeat(np.arange(self.mx), self.ms)
        iI = np.tile(np.arange(self.ms), self.mx)
        blocks = self.kernel[ix[:, None] - ix[None, :] + self.mx - 1, iI[:, None], iI[None, :]]  # (N, N, 3, 3)
        N = ix.size
        return blocks.transpose(2, 0, 3, 1).reshape(3 * N, 3 * N)
