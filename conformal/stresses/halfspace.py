"""Subsurface stresses of a half-space under a solved traction field (issue 24, item 1).

Every element of the traction field is a rectangle carrying a uniform traction (px, py, pn); its
interior stress field is the closed form of :mod:`conformal.stresses.rectangle` (Love 1929 for
the normal load, Cerruti for the tangential loads, written as corner double differences of the
Boussinesq-Cerruti potentials; Johnson 1985 eqs. 3.19-3.22), and the stresses of the field are the
superposition over the elements (the half-space is linear).  Half-space stresses depend on
Poisson's ratio only, not on the shear modulus.

* :func:`stresses` sums directly at any points (planar grids and conformal strips);
* :func:`planar_planes` does the same on depth planes below a planar grid's element centres by
  FFT: the influence of element j on a point at the same depth below element i depends on the
  offset i - j only, so each plane is a zero-padded 2-D convolution (Kalker 1990, §5.4);
* :func:`curved_planes` gives the stresses below a conformal strip (each element in its own
  frame: tangent along x and along the profile, inner normal) on the lines along the inner
  normals of its element centres; along x the influence is again a convolution (the rail is an
  extrusion), across the profile it is summed column by column.

Frames and signs.  Body 1 (the body the normal n points into; the rail of a wheel-rail scene)
fills z > 0 of its frame (x, y, z = depth along n); the tractions of :class:`conformal.result.
TractionField` act on body 1; pressure is positive, tensile stress is positive.  Body 2 carries
the opposite tractions; its depth runs along -n (``body=2``; the frame (x, y, z) is kept, so
body 2's points have z < 0 in a planar frame).
"""
from __future__ import annotations

import math

import numpy as np

from conformal.errors import InputError
from conformal.stresses.rectangle import _displacement_local, _gauss_rectangle_stress, _stress_from

#: lateral distance (element sizes) within which the closed form is used (else Gauss point forces)
NEAR = 4.0
#: beyond this distance (element sizes) a 2 x 2 Gauss rule of point forces suffices (error < 1e-4 of
#: the element's own contribution, (h / 2r)^4 relative)
FAR = 12.0
#: points x elements evaluated at once by the direct sum (memory bound: about 250 bytes each)
_CHUNK = 200_000


def _check_nu(nu: float) -> float:
    nu = float(nu)
    if not (math.isfinite(nu) and -1.0 < nu < 0.5):
        raise InputError(f"stresses: Poisson's ratio must lie in (-1, 0.5), got {nu!r}")
    return nu


def rectangle_kernel(local: np.ndarray, dx: float, dy: float, nu: float) -> np.ndarray:
    """Stress sigma[..., k, l, j] at ``local`` points (..., 3) (z >= 0) of unit uniform tractions
    p_j on the rectangle [-dx/2, dx/2] x [-dy/2, dy/2] (acting on the body; z into the body).

    Closed form (complex-step derivatives of the displacement primitives) within ``NEAR``
    element sizes laterally, point forces at 3 x 3 Gauss points within ``FAR`` sizes, 2 x 2 beyond.
    """
    p = np.asarray(local, dtype=float)
    shape = p.shape[:-1]
    x, y = p[..., 0].ravel(), p[..., 1].ravel()
    z = np.maximum(p[..., 2].ravel(), 1e-12 * min(dx, dy))     # the surface: z -> 0+
    h = max(dx, dy)
    lat = np.maximum(np.abs(x), np.abs(y))
    r = np.sqrt(x * x + y * y + z * z)
    out = np.empty((x.size, 3, 3, 3))
    near = lat <= NEAR * h
    mid = ~near & (r <= FAR * h)
    far = ~near & ~mid
    if near.any():
        out[near] = _stress_from(lambda a, b, c: _displacement_local(a, b, c, dx, dy, 1.0, nu),
                                 x[near], y[near], z[near], 1.0, nu, h)
    if mid.any():
        out[mid] = _gauss_rectangle_stress(x[mid], y[mid], z[mid], dx, dy, nu, 3)
    if far.any():
        out[far] = _gauss_rectangle_stress(x[far], y[far], z[far], dx, dy, nu, 2)
    return out.reshape(shape + (3, 3, 3))


def _parity(k: int, l: int, j: int, axis: int) -> float:
    """Sign of sigma_kl due to p_j under the reflection x_axis -> -x_axis of the offset: -1 for
    every index equal to the axis (the field of a symmetric rectangle is even or odd)."""
    return -1.0 if ((k == axis) + (l == axis) + (j == axis)) % 2 else 1.0


_PARITY = np.array([[[[_parity(k, l, j, ax) for j in range(3)] for l in range(3)] for k in range(3)]
                    for ax in range(2)])   # (2, 3, 3, 3)


# ----------------------------------------------------------------------------- element sources
def _sources(field, body: int):
    """Loaded elements of a traction field: centres (n, 3), frames (n, 3, 3) (columns: the local
    x, y and depth axes in the output frame), sizes (n, 2) and local tractions (n, 3) on the body.

    Planar grid: output frame (x, y, z), z = depth into body 1.  Conformal strip
    (``field.curved``): output frame = the rail-profile frame (x along the track, y, z down)."""
    if body not in (1, 2):
        raise InputError(f"stresses: body must be 1 or 2, got {body!r}")
    sgn = 1.0 if body == 1 else -1.0
    curved = getattr(field, "curved", None)
    if curved is None:
        g = field.grid
        X, Y = g.mesh()
        pn, px, py = (np.asarray(a, float) for a in (field.pn, field.px, field.py))
        m = (pn != 0) | (px != 0) | (py != 0)
        n = int(m.sum())
        centres = np.stack([X[m], Y[m], np.zeros(n)], axis=-1)
        frames = np.broadcast_to(np.diag([1.0, 1.0, sgn]), (n, 3, 3)).copy()
        sizes = np.broadcast_to([g.dx, g.dy], (n, 2)).copy()
        trac = np.stack([sgn * px[m], sgn * py[m], pn[m]], axis=-1)
        return centres, frames, sizes, trac
    pn, px, ps = (np.asarray(field.side_frame(k), float) for k in ("pn", "px", "py"))
    frames_s = _curved_frames(curved, body)                    # (ms, 3, 3)
    X = np.broadcast_to(curved.x[:, None], curved.shape)
    J = np.broadcast_to(np.arange(curved.ms)[None, :], curved.shape)
    m = (pn != 0) | (px != 0) | (ps != 0)
    centres = np.stack([X[m], curved.y[J[m]], curved.z[J[m]]], axis=-1)
    sizes = np.stack([np.full(int(m.sum()), curved.dx), curved.ds[J[m]]], axis=-1)
    trac = np.stack([sgn * px[m], sgn * ps[m], pn[m]], axis=-1)
    return centres, frames_s[J[m]], sizes, trac


def _curved_frames(curved, body: int = 1) -> np.ndarray:
    """(ms, 3, 3): columns e_x, the tangent t = (0, n_z, -n_y) along s and the depth axis
    (+n for the rail, -n for the wheel) in the rail-profile frame, per column of a CurvedGrid."""
    n = np.asarray(curved.normal, float)
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    ms = n.shape[0]
    R = np.zeros((ms, 3, 3))
    R[:, 0, 0] = 1.0
    R[:, 1, 1], R[:, 2, 1] = n[:, 1], -n[:, 0]
    sgn = 1.0 if body == 1 else -1.0
    R[:, 1, 2], R[:, 2, 2] = sgn * n[:, 0], sgn * n[:, 1]
    return R


def stresses(field, points, *, nu: float, body: int = 1) -> np.ndarray:
    """Stress tensor (N/mm²) at ``points`` (..., 3) (mm) of the half-space under a traction field.

    Parameters
    ----------
    field : TractionField
        A solved field (planar grid, or a conformal strip with ``field.curved``).
    points : array_like (..., 3)
        Planar: (x, y, z) with z the depth into body 1 (z <= 0 for ``body=2``).  Conformal strip:
        the rail-profile frame (x, y, z) of the curved grid; points must lie inside the body.
    nu : float
        Poisson's ratio of the body.
    body : {1, 2}
        Body 1 (tractions as in the field) or body 2 (opposite tractions, depth along -n).

    Returns
    -------
    ndarray (..., 3, 3)
        sigma in the frame of ``points``; tension positive.

    Examples
    --------
    A uniform pressure p on a large square: sigma_zz = -p just below its centre.

    >>> from conformal.grid import PlanarGrid
    >>> from conformal.result import TractionField
    >>> g = PlanarGrid.centred(1, 1, 100.0, 100.0)
    >>> one = np.ones((1, 1))
    >>> f = TractionField(g, pn=100 * one, px=0 * one, py=0 * one, status=one.astype(int))
    >>> round(float(stresses(f, [0.0, 0.0, 0.01], nu=0.3)[2, 2]), 3)
    -100.0
    """
    nu = _check_nu(nu)
    pts = np.asarray(points, dtype=float)
    if pts.shape[-1:] != (3,):
        raise InputError(f"stresses: points must have shape (..., 3), got {pts.shape}")
    shape = pts.shape[:-1]
    P = pts.reshape(-1, 3)
    centres, frames, sizes, trac = _sources(field, body)
    out = np.zeros((P.shape[0], 3, 3))
    if len(centres) == 0:
        return out.reshape(shape + (3, 3))
    # group the elements by size (a planar grid: one group; a strip: one per column width)
    keys = np.round(sizes / sizes.max(), 12)
    _, group = np.unique(keys, axis=0, return_inverse=True)
    for gi in np.unique(group):
        idx = np.flatnonzero(group.ravel() == gi)
        dx, dy = sizes[idx[0]]
        step = max(1, _CHUNK // max(len(idx), 1))
        for a in range(0, P.shape[0], step):
            Pc = P[a:a + step]
            d = Pc[:, None, :] - centres[None, idx, :]                       # (p, e, 3)
            local = np.einsum("pei,eia->pea", d, frames[idx])
            K = rectangle_kernel(local, dx, dy, nu)                          # (p, e, 3, 3, 3)
            s_loc = np.einsum("peklj,ej->pekl", K, trac[idx])
            out[a:a + step] += np.einsum("eak,pekl,ebl->pab", frames[idx], s_loc, frames[idx])
    return out.reshape(shape + (3, 3))


# ----------------------------------------------------------------------------- FFT on depth planes
def _conv_kernel_planes(mx: int, my: int, dx: float, dy: float, z: float, nu: float) -> np.ndarray:
    """Kernel on all offsets (2mx-1, 2my-1, 3, 3, 3) at depth z, from one quadrant and parities."""
    ox = np.arange(mx) * dx
    oy = np.arange(my) * dy
    Q = np.stack(np.meshgrid(ox, oy, [z], indexing="ij"), axis=-1)[:, :, 0, :]
    Kq = rectangle_kernel(Q, dx, dy, nu)                                     # (mx, my, 3, 3, 3)
    K = np.empty((2 * mx - 1, 2 * my - 1, 3, 3, 3))
    K[mx - 1:, my - 1:] = Kq
    K[:mx - 1, my - 1:] = Kq[:0:-1] * _PARITY[0]
    K[mx - 1:, :my - 1] = Kq[:, :0:-1] * _PARITY[1]
    K[:mx - 1, :my - 1] = Kq[:0:-1, :0:-1] * (_PARITY[0] * _PARITY[1])
    return K


def planar_planes(field, depths, *, nu: float, body: int = 1) -> np.ndarray:
    """Stresses on depth planes below the element centres of a planar traction field, by FFT.

    Parameters
    ----------
    field : TractionField
        On a :class:`~conformal.grid.PlanarGrid` (mx, my).
    depths : array_like (nd,)
        Depths (mm, >= 0) below the surface of the body.
    nu : float
        Poisson's ratio of the body.
    body : {1, 2}

    Returns
    -------
    ndarray (nd, mx, my, 3, 3)
        sigma at (x_i, y_k, +-depth) in the field's frame (x, y, z); body 2's depth is -z.
    """
    nu = _check_nu(nu)
    if getattr(field, "curved", None) is not None:
        raise InputError("stresses: planar_planes needs a planar grid; use curved_planes for a conformal strip")
    depths = np.asarray(depths, dtype=float).ravel()
    if depths.size == 0 or np.any(~np.isfinite(depths)) or np.any(depths < 0):
        raise InputError(f"stresses: depths must be finite and >= 0, got {depths}")
    if body not in (1, 2):
        raise InputError(f"stresses: body must be 1 or 2, got {body!r}")
    g = field.grid
    mx, my = g.shape
    sgn = 1.0 if body == 1 else -1.0
    trac = np.stack([sgn * np.asarray(field.px, float), sgn * np.asarray(field.py, float),
                     np.asarray(field.pn, float)], axis=-1)                 # (mx, my, 3) local
    loads = [j for j in range(3) if np.any(trac[..., j] != 0)]
    nfx, nfy = 2 * mx, 2 * my
    T = {j: np.fft.rfft2(trac[..., j], s=(nfx, nfy)) for j in loads}
    D = np.diag([1.0, 1.0, sgn])
    out = np.zeros((depths.size, mx, my, 3, 3))
    for d_i, z in enumerate(depths):
        if not loads:
            break
        K = _conv_kernel_planes(mx, my, g.dx, g.dy, float(z), nu)
        for k in range(3):
            for l in range(k, 3):
                acc = 0.0
                for j in loads:
                    # kernel index 0 is offset -(m-1): conv[i] = sum_j K[i - j + m - 1] t[j]
                    acc = acc + np.fft.rfft2(K[:, :, k, l, j], s=(nfx, nfy)) * T[j]
                full = np.fft.irfft2(acc, s=(nfx, nfy))
                out[d_i, :, :, k, l] = full[mx - 1:2 * mx - 1, my - 1:2 * my - 1]
                out[d_i, :, :, l, k] = out[d_i, :, :, k, l]
    if body == 2:
        out = np.einsum("ak,dxykl,bl->dxyab", D, out, D)
    return out


def curved_planes(field, depths, *, nu: float, body: int = 1, columns=None):
    """Stresses below a conformal strip along the normals of its element centres.

    The point (ix, js, d) lies at depth d along the depth axis of column js (the rail's inner
    normal for body 1, the opposite for body 2) below the centre of element (ix, js).  Each loaded
    element acts in its own frame (:func:`_curved_frames`); along x the influence is a convolution
    (FFT), across the profile a sum over the loaded columns.

    Parameters
    ----------
    field : CurvedTractionField
        With ``field.curved``, the CurvedGrid (side frame).
    depths : array_like (nd,)
    nu : float
    body : {1, 2}
    columns : array_like of int, optional
        Target columns js (of the curved grid); default all.

    Returns
    -------
    sigma : ndarray (nd, mx, nc, 3, 3)
        In the rail-profile frame (x, y, z down).
    points : ndarray (nd, mx, nc, 3)
        The positions (mm, rail-profile frame).
    """
    nu = _check_nu(nu)
    curved = getattr(field, "curved", None)
    if curved is None:
        raise InputError("stresses: curved_planes needs a conformal strip (field.curved)")
    if body not in (1, 2):
        raise InputError(f"stresses: body must be 1 or 2, got {body!r}")
    depths = np.asarray(depths, dtype=float).ravel()
    if depths.size == 0 or np.any(~np.isfinite(depths)) or np.any(depths < 0):
        raise InputError(f"stresses: depths must be finite and >= 0, got {depths}")
    sgn = 1.0 if body == 1 else -1.0
    mx, ms = curved.shape
    cols = np.arange(ms) if columns is None else np.asarray(columns, int)
    pn, px, ps = (np.asarray(field.side_frame(k), float) for k in ("pn", "px", "py"))
    trac = np.stack([sgn * px, sgn * ps, pn], axis=-1)                    # (mx, ms, 3)
    R = _curved_frames(curved, body)
    yz = np.stack([curved.y, curved.z], axis=-1)
    src = [j for j in range(ms) if np.any(trac[:, j] != 0)]
    nd = depths.size
    sigma = np.zeros((nd, mx, cols.size, 3, 3))
    pts = np.zeros((nd, mx, cols.size, 3))
    x = curved.x
    off = (np.arange(2 * mx - 1) - (mx - 1)) * curved.dx                  # x offsets
    nf = 2 * mx
    for c, jt in enumerate(cols):
        below = yz[jt][None, :] + depths[:, None] * R[jt, 1:, 2][None, :]   # (nd, 2)
        pts[:, :, c, 0] = x[None, :]
        pts[:, :, c, 1:] = below[:, None, :]
        if not src:
            continue
        acc = np.zeros((nd, nf // 2 + 1, 3, 3), dtype=complex)
        for js in src:
            d_yz = below - yz[js][None, :]                                   # (nd, 2)
            # local coordinates of (offset, y, z) in the frame of column js (offset >= 0 only)
            lx = np.broadcast_to(off[mx - 1:][:, None], (mx, nd))
            loc = np.empty((mx, nd, 3))
            loc[..., 0] = lx
            loc[..., 1] = (d_yz @ R[js, 1:, 1])[None, :]
            loc[..., 2] = (d_yz @ R[js, 1:, 2])[None, :]
            Kq = rectangle_kernel(loc, curved.dx, float(curved.ds[js]), nu)  # (mx, nd, 3, 3, 3)
            K = np.concatenate([Kq[:0:-1] * _PARITY[0], Kq], axis=0)         # (2mx-1, nd, ...)
            Kt = np.fft.rfft(K, n=nf, axis=0)                                # (nf/2+1, nd, 3,3,3)
            Tt = np.fft.rfft(trac[:, js], n=nf, axis=0)                       # (nf/2+1, 3)
            s_loc = np.einsum("fdklj,fj->fdkl", Kt, Tt)
            Rj = R[js]
            acc += np.einsum("ak,fdkl,bl->dfab", Rj, s_loc, Rj)
        full = np.fft.irfft(acc, n=nf, axis=1)                               # (nd, nf, 3, 3)
        sigma[:, :, c] = full[:, mx - 1:2 * mx - 1]
    return sigma, pts
