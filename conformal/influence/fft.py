"""Lean FFTs along one axis for the influence products: scipy's pocketfft without the dispatch.

Each ``scipy.fft`` call passes through uarray's backend dispatch and a layer that checks, copies
and pads its arguments before it reaches the pocketfft binding.  On the small grids of a wheel-rail
sweep (patch grids of 10 x 10 to 60 x 100 elements) that layer costs as much as the transforms: one
zero-padded product of a 55 x 33 grid took 121 µs through ``scipy.fft`` and 70 µs with the binding
called directly, 66 and 21 µs on a 12 x 10 grid (``numpy.fft``: 107 and 61 µs; one thread, best
of 7 x 200 products on a quiet 2-core machine).

The functions here call that binding (``scipy.fft._pocketfft.pypocketfft``, the same C++ code and
the same arguments as ``scipy.fft`` with ``workers=None``: one thread, no normalisation forward,
1/n backward), so their numbers are bitwise those of ``scipy.fft``.  They always use one thread
(a ``scipy.fft.set_workers`` context does not reach them).  The binding is private, so
the module checks it once on import against ``scipy.fft`` on small arrays of both precisions and
uses ``scipy.fft`` itself where the binding is missing, has another signature or differs
(:data:`DIRECT` says which is in use).  Inputs must be float32/float64 (real) or complex64/
complex128 arrays in native byte order; the callers in :mod:`conformal.influence.halfspace` and
:mod:`conformal.solvers.tangential` pass only such arrays.

>>> x = np.arange(6.0).reshape(2, 3)
>>> bool(np.array_equal(irfft(rfft(x, 4), 4)[:, :3], x))
True
"""
from __future__ import annotations

import numpy as np
from scipy import fft as sfft

__all__ = ["DIRECT", "rfft", "fft", "ifft", "irfft", "rfft2", "irfft2", "padded_product", "padded_product32",
           "doubled", "imag_negligible"]


def _binding():
    """The pocketfft binding when it gives bitwise the numbers of scipy.fft, else None."""
    try:
        from scipy.fft._pocketfft import pypocketfft as pf

        for dtype in (np.float64, np.float32):
            x = (np.arange(15.0).reshape(3, 5) ** 1.5).astype(dtype)
            r = pf.r2c(x, (1,), True, 0, None, 1)
            c = pf.c2c(r.copy(), (0,), True, 0, None, 1)
            b = pf.c2c(c.copy(), (0,), False, 2, None, 1)
            checks = [(r, sfft.rfft(x, axis=1)), (c, sfft.fft(r, axis=0)), (b, sfft.ifft(c, axis=0)),
                      (pf.c2r(b, (1,), 5, False, 2, None, 1), sfft.irfft(b, n=5, axis=1)),
                      (pf.r2c(x, (0, 1), True, 0, None, 1), sfft.rfft2(x)),
                      (pf.c2r(r, (0, 1), 5, False, 2, None, 1), sfft.irfft2(r, s=(3, 5)))]
            if not all(a.dtype == e.dtype and a.shape == e.shape and np.array_equal(a, e) for a, e in checks):
                return None
        return pf
    except Exception:  # noqa: BLE001 - any failure of a private binding: use scipy.fft
        return None


_PF = _binding()
#: True where the module calls pocketfft's binding directly, False where it uses scipy.fft
DIRECT = _PF is not None


def _real(x) -> np.ndarray:
    """x as a float32 or float64 array (other types as float64)."""
    x = np.asarray(x)
    return x if x.dtype in (np.float32, np.float64) else x.astype(np.float64)


def rfft(x: np.ndarray, n: int, axis: int = -1, out: np.ndarray | None = None) -> np.ndarray:
    """The real-to-complex transform of x zero-padded to ``n`` >= x.shape[axis] along ``axis``
    (``scipy.fft.rfft(x, n, axis)``); written into ``out`` (shape with n//2+1 along axis) if given."""
    x = _real(x)
    if _PF is None:
        r = sfft.rfft(x, n=n, axis=axis)
        if out is None:
            return r
        out[...] = r
        return out
    if x.shape[axis] != n:
        shape = list(x.shape)
        shape[axis] = n
        pad = np.zeros(shape, x.dtype)
        index = [slice(None)] * x.ndim
        index[axis] = slice(0, x.shape[axis])
        pad[tuple(index)] = x
        x = pad
    return _PF.r2c(x, (axis % x.ndim,), True, 0, out, 1)


def fft(x: np.ndarray, axis: int, overwrite: bool = False) -> np.ndarray:
    """The complex forward transform along ``axis`` (``scipy.fft.fft``), in place with ``overwrite``."""
    if _PF is None:
        return sfft.fft(x, axis=axis, overwrite_x=overwrite)
    return _PF.c2c(x, (axis % x.ndim,), True, 0, x if overwrite else None, 1)


def ifft(x: np.ndarray, axis: int, overwrite: bool = False) -> np.ndarray:
    """The complex backward transform along ``axis`` divided by its length (``scipy.fft.ifft``),
    in place with ``overwrite``."""
    if _PF is None:
        return sfft.ifft(x, axis=axis, overwrite_x=overwrite)
    return _PF.c2c(x, (axis % x.ndim,), False, 2, x if overwrite else None, 1)


def irfft(x: np.ndarray, n: int, axis: int = -1) -> np.ndarray:
    """The complex-to-real backward transform of the half-spectrum x (n//2+1 along ``axis``) to
    ``n`` real values, divided by n (``scipy.fft.irfft(x, n, axis)``)."""
    if _PF is None:
        return sfft.irfft(x, n=n, axis=axis)
    return _PF.c2r(x, (axis % x.ndim,), n, False, 2, None, 1)


def rfft2(x: np.ndarray) -> np.ndarray:
    """``scipy.fft.rfft2(x)``: the real-to-complex transform over the last two axes."""
    x = _real(x)
    if _PF is None:
        return sfft.rfft2(x)
    return _PF.r2c(x, (x.ndim - 2, x.ndim - 1), True, 0, None, 1)


def irfft2(x: np.ndarray, s: tuple[int, int]) -> np.ndarray:
    """``scipy.fft.irfft2(x, s)`` for a half-spectrum x of shape (..., s[0], s[1]//2+1)."""
    if _PF is None:
        return sfft.irfft2(x, s=s)
    if x.shape[-2:] != (s[0], s[1] // 2 + 1):
        raise ValueError(f"irfft2: a half-spectrum of shape {x.shape[-2:]} does not belong to s = {s}")
    return _PF.c2r(x, (x.ndim - 2, x.ndim - 1), s[1], False, 2, None, 1)


def padded_product(p: np.ndarray, kernel_hat: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The zero-padded FFT convolution of one real field p (mx, my) with a kernel given by its
    (Mx, My//2+1) half-spectrum ``kernel_hat`` on the padded (Mx, My) = ``shape`` grid, restricted
    to the first mx x my entries: the mx non-zero rows transformed along y straight into the
    padded half-spectrum, the transforms along x, the product, and only mx rows transformed back.

    The same transforms, in the same order and on the same arrays, as :func:`rfft`, :func:`fft`,
    :func:`ifft` and :func:`irfft` called one after the other (so bitwise their numbers), in one
    call: on the patch grids of a wheel-rail sweep the Python layers around the four transforms
    were a tenth of the product's time."""
    mx, my = p.shape
    Mx, My = shape
    if _PF is None or p.dtype != np.float64:
        spec = np.zeros((Mx, My // 2 + 1), dtype=complex)
        rfft(p, My, axis=-1, out=spec[:mx])
        spec = fft(spec, axis=-2, overwrite=True)
        spec *= kernel_hat
        return irfft(ifft(spec, axis=-2, overwrite=True)[:mx], My, axis=-1)[:, :my]
    x = np.zeros((mx, My))
    x[:, :my] = p
    spec = np.zeros((Mx, My // 2 + 1), dtype=complex)
    _PF.r2c(x, (1,), True, 0, spec[:mx], 1)
    _PF.c2c(spec, (0,), True, 0, spec, 1)
    spec *= kernel_hat
    _PF.c2c(spec, (0,), False, 2, spec, 1)
    return _PF.c2r(spec[:mx], (1,), My, False, 2, None, 1)[:, :my]


def padded_product32(p: np.ndarray, kernel2: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """:func:`padded_product` in single precision for a kernel with a real half-spectrum: p (mx, my)
    as float32, ``kernel2`` the (Mx, 2 (My//2+1)) float32 real spectrum with each value
    :func:`doubled`, so that the product in Fourier space runs on the float32 view of the complex64
    spectrum.  Returns float32 (mx, my); relative error about 1e-7 (float32 rounding)."""
    mx, my = p.shape
    Mx, My = shape
    x = np.zeros((mx, My), dtype=np.float32)
    x[:, :my] = p
    spec = np.zeros((Mx, My // 2 + 1), dtype=np.complex64)
    rfft(x, My, axis=-1, out=spec[:mx])
    spec = fft(spec, axis=-2, overwrite=True)
    spec.view(np.float32)[...] *= kernel2
    return irfft(ifft(spec, axis=-2, overwrite=True)[:mx], My, axis=-1)[:, :my]


def doubled(v: np.ndarray) -> np.ndarray:
    """Each value of ``v`` twice along its last axis (``numpy.repeat(v, 2, axis=-1)``, the same
    array by two strided copies rather than numpy's copy per element): a real spectral factor on
    the float view of a complex spectrum (real and imaginary part side by side)."""
    out = np.empty(v.shape[:-1] + (2 * v.shape[-1],), dtype=v.dtype)
    out[..., 0::2] = v
    out[..., 1::2] = v
    return out


def imag_negligible(v: np.ndarray, rtol: float) -> bool:
    """max |Im v| <= rtol max |v| (a spectrum real to rounding), the moduli computed only where the
    real parts do not decide it (max |v| >= max |Re v|, so max |Im v| <= rtol max |Re v| implies it)."""
    im = np.abs(v.imag).max()
    if im <= rtol * np.abs(v.real).max():
        return True
    return bool(im <= rtol * np.abs(v).max())
