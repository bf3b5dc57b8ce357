"""Influence numbers in files: CONTACT's file of numerical influence coefficients (C3 = 9) and the
project's own strip format.

**CONTACT's format** (user guide, appendix "Specification of the file of numerical influence
coefficients", section ``sec:spec_inflcf``, equation ``eq:ui_sum_Cij_pj``).  The file holds the
coefficients C of

    u_i(x_I) = (1/G) sum_j sum_J C_IiJj p_j(x_J),      i, j in {n, x, y},

dimension mm (displacement times G per traction), for the combined bodies (G the combined shear
modulus, 1/G = (1/G1 + 1/G2)/2).  Layout, free format, ``%`` starts a comment::

    nmatrix   iaconvex                  1 matrix for all loads, or my (one per loaded row jy)
    lquasid   xyzorder                  0 (9 coefficients per point) and 312 (n, x, y order)
    lsymmx    lsymmy                    1 (symmetry in x) and 0 (none in y)
    mxfile    myfile   dxfile  dyfile   the file's grid
    % empty/comment line
    % empty/comment line
    for imatrix = 1..nmatrix:
        if nmatrix > 1:  % empty/comment line,  then  imatrix  xcentr  ycentr
        for iyofs = -my+1 .. my-1:  two empty/comment lines, then for ixofs = 0 .. mx-1:
            ixofs  xrel  Czz Czx Czy  Cxz Cxx Cxy  Cyz Cyx Cyy

ixofs = ix - jx and iyofs = iy - jy are the offsets of the observed from the loaded element; the
coefficients at -ixofs follow by symmetry in x, the components nx, xn, xy and yx changing sign
(CONTACT's reader, src/m_inflcf.f90, does the same).  ``C_ij`` is the displacement i due to the
traction j.  The guide asks for exactly these comment lines; :func:`read_contact_file` accepts
any number of empty and ``%`` lines between the numbers (the numbers alone fix the layout), so
files written with CONTACT's own writer, which puts three comment lines per offset, read too.
A file grid larger than the computation's is cut (as CONTACT does); :meth:`ContactInfluenceFile.kernel`
pads a smaller one with zeros as CONTACT does, but ``[model] influence_file`` refuses it (CONTACT
warns that the padding is inaccurate).

Mapping onto the project's kernel (:mod:`conformal.influence.curved`, components (x, s, n), n into
body 1, u the displacement difference body 1 - body 2, as in :mod:`conformal.influence.halfspace`
and as in CONTACT): K[ix - jx, iy, jy, a, b] = C_(a b)(ix - jx, iy - jy; jy) / G with y = s.

**The project's strip format** (``conformal-influence 1``) keeps non-uniform widths along s and
kernels without symmetry in x (finite-element strips, conformal.influence.fe); see
:func:`write_influence_file`.  ``[model] influence_file`` reads either: a file whose first line is
``conformal-influence 1`` in the project's format, any other in CONTACT's.

>>> import numpy as np, io
>>> from conformal.influence.curved import curved_halfspace_kernel
>>> from conformal.materials import Material
>>> mat = Material.steel()
>>> K = curved_halfspace_kernel(3, 0.5, np.arange(2) * 0.4, np.full(2, 0.4), np.zeros(2), mat)
>>> buf = io.StringIO()
>>> write_contact_file(buf, K, dx=0.5, dy=0.4, G=mat.G)
>>> _ = buf.seek(0)
>>> f = read_contact_file(buf)
>>> f.nmatrix, f.mx, f.my, bool(np.allclose(f.kernel(mat.G), K, rtol=1e-15, atol=0))
(1, 3, 2, True)

The project's own format:

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


def influence_operator(path, *, mx: int, ms: int, dx: float, ds, K: float = 0.0, G: float | None = None):
    """Read an influence file and return its operator for a grid of mx x ms elements (dx, widths ds
    along s), checking that the file belongs to that grid.  A file in CONTACT's format (any file
    not starting with ``conformal-influence``) needs ``G``, the combined shear modulus that turns
    its coefficients into displacements (user guide eq. ``eq:ui_sum_Cij_pj``)."""
    name = f"[model] influence_file {Path(str(path)).name}"
    if not _is_project_format(path):
        if G is None:
            raise InputError(f"{name}: a CONTACT influence file needs the combined shear modulus G")
        f = read_contact_file(path)
        widths = np.broadcast_to(np.asarray(ds, dtype=float), (int(ms),))
        if not np.allclose(widths, widths[0], rtol=1e-9, atol=0):
            raise InputError(f"{name}: CONTACT's file has one dy; the grid's widths along s differ")
        f.check_grid(dx, float(widths[0]), name=name)
        if f.mx < mx or f.my < ms:
            raise InputError(f"{name}: the file's grid ({f.mx} x {f.my}) is smaller than the computation's "
                             f"({mx} x {ms}); CONTACT would pad with zeros, which is inaccurate: refused")
        op = FileInfluence.from_kernel(f.kernel(G, mx=mx, my=ms))
        object.__setattr__(op, "K", float(K))
        return op
    f = read_influence_file(path)
    f.check_grid(mx, ms, dx, ds, name=name)
    return f.operator(K)


def _is_project_format(path) -> bool:
    p = Path(str(path))
    if not p.is_file():
        raise InputError(f"influence file not found: {p}")
    with open(p, encoding="ascii", errors="replace") as fh:
        for raw in fh:
            line = raw.strip()
            if line and not line.startswith(("#", "%")):
                return line.split()[0] == FORMAT
    return False


# ----------------------------------------------------------------------------- CONTACT's format
#: CONTACT's component order n, x, y -> the project's (x, s, n) indices
_NXY = (2, 0, 1)
#: the components whose coefficient changes sign at -ixofs: nx, xn, xy, yx (CONTACT's order n, x, y)
_ODD_X = np.array([[1.0, -1.0, 1.0], [-1.0, 1.0, -1.0], [1.0, -1.0, 1.0]])


@dataclass(frozen=True, eq=False)
class ContactInfluenceFile:
    """A file of numerical influence coefficients in CONTACT's format.

    ``C[imatrix, iyofs + my - 1, ixofs, i, j]`` (ixofs = 0 .. mx-1, components n, x, y), in mm
    (user guide eq. ``eq:ui_sum_Cij_pj``: u = C p / G); ``centres`` the (xcentr, ycentr) of each
    matrix (zeros for a single matrix).
    """

    C: np.ndarray
    dx: float
    dy: float
    iaconvex: int = 1
    centres: np.ndarray | None = None

    @property
    def nmatrix(self) -> int:
        return self.C.shape[0]

    @property
    def mx(self) -> int:
        return self.C.shape[2]

    @property
    def my(self) -> int:
        return (self.C.shape[1] + 1) // 2

    def check_grid(self, dx: float, dy: float, name: str = "influence file") -> None:
        """InputError unless the file's dx, dy are the grid's (CONTACT's tolerance 1e-5 mm)."""
        if abs(self.dx - dx) > 1e-5 or abs(self.dy - dy) > 1e-5:
            raise InputError(f"{name}: the file's dx, dy = {self.dx:g}, {self.dy:g} mm; the grid's are "
                             f"{dx:g}, {dy:g} mm")

    def kernel(self, G: float, *, mx: int | None = None, my: int | None = None) -> np.ndarray:
        """The project's kernel (2mx-1, my, my, 3, 3), components (x, s, n), in mm/(N/mm²): C/G,
        mirrored to negative x-offsets; for a grid of mx x my elements (default the file's), the
        file's numbers padded with zeros or cut (user guide, same appendix)."""
        if not (G > 0 and np.isfinite(G)):
            raise InputError(f"influence file: G must be > 0, got {G!r}")
        mx = self.mx if mx is None else int(mx)
        my = self.my if my is None else int(my)
        if self.nmatrix > 1 and self.nmatrix != my:
            raise InputError(f"influence file: {self.nmatrix} matrices (one per row) for a grid of {my} rows")
        nx = min(mx, self.mx)
        # half kernel H[ixofs, jmat, iyofs + my - 1, a, b] in the project's component order
        Cp = np.zeros((self.nmatrix, 2 * my - 1, mx, 3, 3))
        ny = min(my, self.my)
        Cp[:, my - ny: my + ny - 1, :nx] = self.C[:, self.my - ny: self.my + ny - 1, :nx]
        Cp = Cp[..., list(_NXY_INV), :][..., list(_NXY_INV)] / G
        mirror = _ODD_X[np.ix_(_NXY_INV, _NXY_INV)]
        I = np.arange(my)
        off = I[:, None] - I[None, :] + my - 1                       # (iy, jy) -> iyofs index
        jm = np.zeros_like(off) if self.nmatrix == 1 else np.broadcast_to(I[None, :], off.shape)
        half = Cp[jm, off]                                            # (my, my, mx, 3, 3)
        half = np.moveaxis(half, 2, 0)                                # (mx, my, my, 3, 3)
        K = np.empty((2 * mx - 1, my, my, 3, 3))
        K[mx - 1:] = half
        K[:mx - 1] = half[:0:-1] * mirror
        return K


#: the inverse: the project's (x, s, n) index -> CONTACT's (n, x, y) index
_NXY_INV = (1, 2, 0)


def write_contact_file(target, kernel: np.ndarray, *, dx: float, dy: float, G: float, iaconvex: int = 1,
                       comments=()) -> None:
    """Write a kernel (2mx-1, my, my, 3, 3), components (x, s, n) in mm/(N/mm²), as CONTACT's file
    of numerical influence coefficients (layout in the module docstring), with G the combined shear
    modulus (C = G K).  One matrix when the kernel depends on iy - jy only (a uniform strip), else
    one per loaded row.  The kernel must have CONTACT's symmetry in x (lsymmx = 1).  ``target`` a
    path (written atomically) or a text stream; ``iaconvex`` (1: the rail, 2: the wheel is the
    upper body) is recorded for CONTACT."""
    K = _check_kernel(kernel)
    nk, my = K.shape[0], K.shape[1]
    mx = (nk + 1) // 2
    if not (dx > 0 and dy > 0 and G > 0):
        raise InputError(f"influence file: dx, dy, G must be > 0, got {dx}, {dy}, {G}")
    if iaconvex not in (1, 2):
        raise InputError(f"influence file: iaconvex must be 1 or 2, got {iaconvex}")
    mirror = _ODD_X[np.ix_(_NXY_INV, _NXY_INV)]
    scale = float(np.abs(K).max()) or 1.0
    if np.abs(K[:mx - 1] - K[mx:][::-1] * mirror).max(initial=0.0) > 1e-12 * scale:
        raise InputError("influence file: CONTACT's format needs symmetry in x (K(-ix) = K(ix) with nx, xn, "
                         "xs, sx changing sign); this kernel does not have it")
    I = np.arange(my)
    d = I[:, None] - I[None, :]
    T = np.where((d >= 0)[None, :, :, None, None], K[:, np.maximum(d, 0), 0], K[:, 0, np.maximum(-d, 0)])
    toeplitz = bool(np.array_equal(T, K))
    C = G * K[mx - 1:][..., list(_NXY), :][..., list(_NXY)]           # (mx, iy, jy, n x y, n x y)
    nmatrix = 1 if toeplitz else my
    out = io.StringIO()
    for c in comments:
        out.write(f"% {c}\n")
    out.write(f"{nmatrix:4d} {iaconvex:4d}      % nmatrix, iaconvex\n")
    out.write(f"{0:4d} {312:4d}      % lquasid, xyzorder: 9 coefficients per point, order n, x, y\n")
    out.write(f"{1:4d} {0:4d}      % lsymmx, lsymmy: symmetry in x, none in y\n")
    out.write(f"{mx:4d} {my:4d} {float(dx)!r} {float(dy)!r}   % mx, my, dx, dy\n")
    out.write(f"% influence coefficients C (mm): u_i = C_ij p_j / G, G = {float(G)!r} N/mm2\n")
    out.write("%\n")
    for imat in range(nmatrix):
        if nmatrix > 1:
            out.write("%\n")
            out.write(f"{imat + 1:4d} {0.0!r} {float((imat + 0.5) * dy)!r}   % imatrix, xcentr, ycentr\n")
        for iyofs in range(-my + 1, my):
            out.write(f"% offset iyofs = {iyofs} (y = {iyofs * dy:g} mm)\n")
            out.write("% ixofs  xrel  Czz Czx Czy  Cxz Cxx Cxy  Cyz Cyx Cyy\n")
            jy = 0 if nmatrix == 1 else imat
            iy = (jy + iyofs) if nmatrix > 1 else (iyofs if iyofs >= 0 else 0)
            jy = jy if nmatrix > 1 else (0 if iyofs >= 0 else -iyofs)
            for ix in range(mx):
                vals = C[ix, iy, jy].ravel() if 0 <= iy < my else np.zeros(9)
                out.write(f"{ix:4d} {ix * float(dx)!r} " + " ".join(f"{v:.17g}" for v in vals) + "\n")
    text = out.getvalue()
    if hasattr(target, "write"):
        target.write(text)
        return
    write_text(target, text, encoding="ascii")


def _numbers(line: str, name: str, lineno: int) -> list[float]:
    try:
        return [float(v.replace("d", "e").replace("D", "E")) for v in line.replace(",", " ").split()]
    except ValueError:
        raise InputError(f"{name}, line {lineno}: expected numbers, got {line.strip()[:60]!r}") from None


def _source_text(source) -> tuple[str, str]:
    """(text, name) of an influence file given as a path or a text stream (both readers)."""
    if hasattr(source, "read"):
        return source.read(), getattr(source, "name", None) or "influence file"
    path = Path(source)
    if not path.is_file():
        raise InputError(f"influence file not found: {path}")
    data = path.read_bytes()
    if b"\0" in data[:4096]:     # an NPZ, a zip, a binary: say so rather than echo its bytes
        raise InputError(f"{path.name}: a binary file, not an influence file (text: CONTACT's format or "
                         f"the project's {FORMAT!r}, see conformal.influence.contact_file)")
    return data.decode("ascii", errors="replace"), path.name


def read_contact_file(source) -> ContactInfluenceFile:
    """Read CONTACT's file of numerical influence coefficients (path or text stream); the layout of
    the module docstring, checked as CONTACT checks it (lquasid = 0, xyzorder = 312, lsymmx = 1,
    lsymmy = 0, nmatrix 1 or my)."""
    text, name = _source_text(source)
    rows = []
    for k, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("%")[0].strip()
        if line:
            rows.append((k, line))
    if len(rows) < 4:
        raise InputError(f"{name}: CONTACT influence file needs 4 header lines, found {len(rows)}")
    head = [_numbers(line, name, k) for k, line in rows[:4]]
    try:
        nmatrix, iaconvex = int(head[0][0]), int(head[0][1])
        lquasid, xyzorder = int(head[1][0]), int(head[1][1])
        lsymmx, lsymmy = int(head[2][0]), int(head[2][1])
        mx, my, dx, dy = int(head[3][0]), int(head[3][1]), float(head[3][2]), float(head[3][3])
    except IndexError:
        raise InputError(f"{name}: header needs 'nmatrix iaconvex', 'lquasid xyzorder', 'lsymmx lsymmy', "
                         f"'mx my dx dy'") from None
    if lquasid != 0 or xyzorder != 312:
        raise InputError(f"{name}: lquasid = {lquasid}, xyzorder = {xyzorder}; CONTACT reads only lquasid = 0 "
                         f"(9 coefficients) in order 312 (n, x, y)")
    if lsymmx != 1 or lsymmy != 0:
        raise InputError(f"{name}: lsymmx = {lsymmx}, lsymmy = {lsymmy}; the format needs symmetry in x only (1, 0)")
    if mx < 1 or my < 1 or not (dx > 0 and dy > 0):
        raise InputError(f"{name}: bad grid mx, my, dx, dy = {mx}, {my}, {dx}, {dy}")
    if nmatrix not in (1, my):
        raise InputError(f"{name}: nmatrix = {nmatrix}; must be 1 or my = {my}")
    per_matrix = (2 * my - 1) * mx
    need = nmatrix * per_matrix + (nmatrix if nmatrix > 1 else 0)
    body = rows[4:]
    if len(body) != need:
        raise InputError(f"{name}: expected {need} lines of numbers after the header, found {len(body)}")
    C = np.empty((nmatrix, 2 * my - 1, mx, 3, 3))
    centres = np.zeros((nmatrix, 2))
    pos = 0
    for imat in range(nmatrix):
        if nmatrix > 1:
            k, line = body[pos]
            v = _numbers(line, name, k)
            if len(v) < 3 or int(v[0]) != imat + 1:
                raise InputError(f"{name}, line {k}: expected 'imatrix xcentr ycentr' for matrix {imat + 1}")
            centres[imat] = v[1:3]
            pos += 1
        for jo in range(2 * my - 1):
            for ix in range(mx):
                k, line = body[pos]
                v = _numbers(line, name, k)
                if len(v) < 11 or int(v[0]) != ix:
                    raise InputError(f"{name}, line {k}: expected 'ixofs xrel' and 9 coefficients for ixofs = {ix}")
                C[imat, jo, ix] = np.reshape(v[2:11], (3, 3))
                pos += 1
    if not np.all(np.isfinite(C)):
        raise InputError(f"{name}: contains NaN or infinite values")
    return ContactInfluenceFile(C=C, dx=dx, dy=dy, iaconvex=iaconvex, centres=centres)


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
    text, name = _source_text(source)
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
