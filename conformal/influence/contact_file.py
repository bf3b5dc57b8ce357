"""Export and import of influence numbers as a text file in the layout of CONTACT's file of
numerical influence coefficients.

CONTACT (Vollebregt) can read influence numbers computed elsewhere (user guide, appendix
"Specification of the file of numerical influence coefficients").  Its layout is the x-invariant
kernel of a curved strip, (2mx-1, ms, ms, 3, 3) (invariant along x), which is the layout of
:class:`~conformal.influence.curved.CurvedInfluence`.  The guide was not available here, so the
exact CONTACT column order, header keywords and units line could NOT be verified: this module
writes a documented, self-describing text format with that layout, reads it back exactly
(round trip to the last bit with ``%.17g``), and is the place to adapt once the appendix is at hand.

Numbers read from a file are used by the solvers through :func:`influence_operator` (an operator with
the interface of :class:`~conformal.influence.curved.CurvedInfluence`); in a scene,
``[model] influence_file = "numbers.txt"`` (theory "exact") replaces the half-space numbers of the
planar grid by the file's, which must be for that grid (mx x my elements, dx, widths dy).

Format (ASCII, ``#`` starts a comment, blank lines ignored)::

    # any comment lines
    conformal-influence 1            format name and version
    mx <mx> ms <ms>                  elements along x and along s
    dx <dx>                          element length along x (mm)
    s_edges <ms+1 values>            element edges along the arc length s (mm)
    components x s n                 component order of i (displacement) and j (traction)
    units mm/(N/mm2)                 displacement per unit traction
    data                             then (2mx-1) ms ms lines:
    <kx> <I> <J> <A_xx> <A_xs> <A_xn> <A_sx> <A_ss> <A_sn> <A_nx> <A_ns> <A_nn>

where kx = ix - jx runs from -(mx-1) to mx-1 (the x-offset of the observed element from the
loaded one), I the observed and J the loaded element along s (0-based), and A_ij the displacement
difference u_i at (ix, I) per unit traction p_j at (jx, J), components in each element's contact
frame (n into body 1), as in conformal.influence.curved.

>>> import numpy as np, io
>>> K = np.arange(3 * 2 * 2 * 9, dtype=float).reshape(3, 2, 2, 3, 3)
>>> buf = io.StringIO()
>>> write_influence_file(buf, K, dx=0.5, s_edges=[0.0, 0.4, 0.8])
>>> _ = buf.seek(0)
>>> f = read_influence_file(buf)
>>> bool(np.array_equal(f.kernel, K)), f.mx, f.ms, f.dx
(True, 2, 2, 0.5)
"""
from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from conformal.errors import InputError
from conformal.files import write_text
from conformal.influence.curved import CurvedInfluence

FORMAT = "conformal-influence"
VERSION = 1


@dataclass(frozen=True, eq=False)
class InfluenceFile:
    """Contents of an influence file."""

    kernel: np.ndarray       # (2mx-1, ms, ms, 3, 3)
    dx: float
    s_edges: np.ndarray      # (ms+1,)
    comments: tuple[str, ...] = ()

    @property
    def mx(self) -> int:
        return (self.kernel.shape[0] + 1) // 2

    @property
    def ms(self) -> int:
        return self.kernel.shape[1]

    def check_grid(self, mx: int, ms: int, dx: float, ds, name: str = "influence file") -> None:
        """InputError unless the file is for mx x ms elements of length dx and widths ds along s
        (relative tolerance 1e-6)."""
        if (self.mx, self.ms) != (int(mx), int(ms)):
            raise InputError(f"{name}: the file is for {self.mx} x {self.ms} elements, the grid has {mx} x {ms}")
        if abs(self.dx - dx) > 1e-6 * dx:
            raise InputError(f"{name}: the file's dx = {self.dx:g} mm, the grid's dx = {dx:g} mm")
        widths = np.diff(self.s_edges)
        if not np.allclose(widths, np.broadcast_to(np.asarray(ds, dtype=float), widths.shape), rtol=1e-6, atol=0):
            raise InputError(f"{name}: the file's element widths along s differ from the grid's")

    def operator(self, K: float = 0.0):
        """The influence operator of the file's numbers (:class:`FileInfluence`, the interface of
        conformal.influence.curved.CurvedInfluence that the normal and tangential solvers take);
        ``K`` is only reported (the coupling is in the numbers themselves)."""
        op = FileInfluence.from_kernel(self.kernel)
        object.__setattr__(op, "K", float(K))
        return op


@dataclass(frozen=True, eq=False)
class FileInfluence(CurvedInfluence):
    """Influence numbers read from a file, as an x-invariant strip operator; ``K`` for reports."""

    K: float = 0.0


def influence_operator(path, *, mx: int, ms: int, dx: float, ds, K: float = 0.0):
    """Read an influence file and return its operator for a grid of mx x ms elements (dx, widths ds
    along s), checking that the file belongs to that grid."""
    f = read_influence_file(path)
    f.check_grid(mx, ms, dx, ds, name=f"[model] influence_file {Path(str(path)).name}")
    return f.operator(K)


def _check_kernel(kernel: np.ndarray) -> np.ndarray:
    K = np.asarray(kernel, dtype=float)
    if K.ndim != 5 or K.shape[0] % 2 != 1 or K.shape[1] != K.shape[2] or K.shape[3:] != (3, 3):
        raise InputError(f"influence kernel: need shape (2mx-1, ms, ms, 3, 3), got {K.shape}")
    if not np.all(np.isfinite(K)):
        raise InputError("influence kernel: contains NaN or infinite values")
    return K


def write_influence_file(target, kernel: np.ndarray, *, dx: float, s_edges, comments=()) -> None:
    """Write a kernel (2mx-1, ms, ms, 3, 3) to ``target`` (path or text stream); atomic for paths."""
    K = _check_kernel(kernel)
    nk, ms = K.shape[0], K.shape[1]
    mx = (nk + 1) // 2
    e = np.asarray(s_edges, dtype=float)
    if e.shape != (ms + 1,) or np.any(np.diff(e) <= 0):
        raise InputError(f"influence file: s_edges must be {ms + 1} increasing values, got shape {e.shape}")
    if not dx > 0:
        raise InputError(f"influence file: dx must be > 0, got {dx}")
    kx, I, J = np.meshgrid(np.arange(nk) - (mx - 1), np.arange(ms), np.arange(ms), indexing="ij")
    idx = np.column_stack([kx.ravel(), I.ravel(), J.ravel()])
    vals = K.reshape(-1, 9)
    buf = io.StringIO()
    for c in comments:
        buf.write(f"# {c}\n")
    buf.write(f"{FORMAT} {VERSION}\n")
    buf.write(f"mx {mx} ms {ms}\n")
    buf.write(f"dx {float(dx)!r}\n")
    buf.write("s_edges " + " ".join(repr(float(v)) for v in e) + "\n")
    buf.write("components x s n\nunits mm/(N/mm2)\ndata\n")
    body = np.column_stack([idx.astype(float), vals])
    np.savetxt(buf, body, fmt=["%d", "%d", "%d"] + ["%.17g"] * 9)
    text = buf.getvalue()
    if hasattr(target, "write"):
        target.write(text)
        return
    write_text(target, text, encoding="ascii")


def read_influence_file(source) -> InfluenceFile:
    """Read a file written by :func:`write_influence_file` (path or text stream)."""
    name = getattr(source, "name", None) or "influence file"
    if hasattr(source, "read"):
        text = source.read()
    else:
        path = Path(source)
        if not path.is_file():
            raise InputError(f"influence file not found: {path}")
        text = path.read_text(encoding="ascii", errors="replace")
        name = path.name
    comments, header, data_start = [], {}, None
    lines = text.splitlines()
    for k, raw in enumerate(lines):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            comments.append(line[1:].strip())
            continue
        words = line.split()
        if words[0] == "data":
            data_start = k + 1
            break
        header[words[0]] = words[1:]
    if header.get(FORMAT) != [str(VERSION)]:
        raise InputError(f"{name}: not a '{FORMAT} {VERSION}' influence file")
    if data_start is None:
        raise InputError(f"{name}: no 'data' line")
    try:
        mx, ms = int(header["mx"][0]), int(header["mx"][2])
        if header["mx"][1] != "ms":
            raise ValueError
        dx = float(header["dx"][0])
        s_edges = np.array([float(v) for v in header["s_edges"]])
    except (KeyError, IndexError, ValueError):
        raise InputError(f"{name}: bad header (need 'mx <mx> ms <ms>', 'dx <dx>', 's_edges ...')") from None
    if header.get("components") != ["x", "s", "n"]:
        raise InputError(f"{name}: unsupported component order {header.get('components')}")
    if mx < 1 or ms < 1 or s_edges.size != ms + 1:
        raise InputError(f"{name}: header sizes disagree (mx {mx}, ms {ms}, {s_edges.size} s_edges)")
    try:
        data = np.loadtxt(io.StringIO("\n".join(lines[data_start:])), ndmin=2)
    except ValueError as exc:
        raise InputError(f"{name}: bad data line ({exc})") from None
    n = (2 * mx - 1) * ms * ms
    if data.shape != (n, 12):
        raise InputError(f"{name}: expected {n} data lines of 12 numbers, got {data.shape[0]} x "
                         f"{data.shape[1] if data.ndim == 2 else 0}")
    kx, I, J = data[:, 0].astype(int) + (mx - 1), data[:, 1].astype(int), data[:, 2].astype(int)
    if (kx.min() < 0 or kx.max() > 2 * mx - 2 or I.min() < 0 or I.max() >= ms or J.min() < 0 or J.max() >= ms):
        raise InputError(f"{name}: element index out of range")
    K = np.full((2 * mx - 1, ms, ms, 3, 3), np.nan)
    K[kx, I, J] = data[:, 3:].reshape(-1, 3, 3)
    if np.isnan(K).any():
        raise InputError(f"{name}: some (kx, I, J) entries are missing or repeated")
    return InfluenceFile(K, dx, s_edges, tuple(comments))
