"""Atomic file writes: every file the package writes goes through this module.

A file is written to a temporary name beside its target (same folder, so the rename stays on one
file system), flushed to disk and renamed over the target (``os.replace``, atomic on POSIX and
Windows).  A write that fails (a full disk, an interrupt, an exception of the writer) removes the
temporary file and leaves the target as it was: never a 0-byte or half-written file.  The
temporary file is created with mode 0666 less the process's umask, as ``open`` would create the
target itself (``tempfile.mkstemp`` makes 0600 files, which other users of a shared folder,
e.g. a shared influence cache, could not read).

Temporary names are ``.<name>.<8 hex>.tmp`` (:func:`is_temporary`), or ``.<name>.<8 hex>.tmp<suffix>``
for writers that pick the format from the name (matplotlib, meshio, pyvista: ``keep_suffix``).
:func:`check_output_path` refuses an output path before the work that fills it;
:func:`read_npz` turns a truncated NPZ file into one ValueError (not zipfile's BadZipFile).

>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
>>> write_text(p, "one\\n")
>>> p.read_text()
'one\\n'
>>> is_temporary(".a.txt.0123abcd.tmp.txt"), is_temporary("a.txt")
(True, False)
"""
from __future__ import annotations

import contextlib
import os
import re
import secrets
from pathlib import Path
from typing import IO, Iterator

from conformal.errors import InputError

__all__ = ["atomic_path", "open_atomic", "write_text", "write_bytes", "save_npz_atomic", "save_figure",
           "read_npz", "is_temporary", "check_output_path"]

_TEMP = re.compile(r"^\..+\.[0-9a-f]{8}\.tmp(\.[A-Za-z0-9]+)?$")


def is_temporary(name: str) -> bool:
    """Whether a file name is one of this module's temporary names."""
    return bool(_TEMP.match(name))


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, keep_suffix: bool = False, make_parents: bool = True
                ) -> Iterator[Path]:
    """A temporary path beside ``path`` for a writer that opens files by name (``keep_suffix``:
    the temporary name ends in the suffix of ``path``, for writers that choose the format by it).

    When the block ends normally the temporary file is synced and renamed to ``path``; when it
    raises, the temporary file is removed and ``path`` is untouched.  The temporary file exists
    (empty, mode 0666 less the umask) when the block starts.
    """
    path = Path(path)
    if make_parents:
        path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp" + (path.suffix if keep_suffix else ""))
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            break
        except FileExistsError:
            continue
    try:
        yield tmp
        _fsync(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.filename is None:    # a failed write names no file: name the target
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
        raise


@contextlib.contextmanager
def open_atomic(path: str | os.PathLike, mode: str = "w", **kwargs) -> Iterator[IO]:
    """``open(path, mode, **kwargs)`` on a temporary file that replaces ``path`` when the block
    ends normally (``mode``: "w" or "wb"); see :func:`atomic_path`."""
    if mode not in ("w", "wb"):
        raise ValueError(f"open_atomic: mode must be 'w' or 'wb', got {mode!r}")
    with atomic_path(path) as tmp:
        with open(tmp, mode, **kwargs) as fh:
            yield fh
            fh.flush()


def write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically."""
    with open_atomic(path, "w", encoding=encoding, newline="") as fh:
        fh.write(text)


def write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with open_atomic(path, "wb") as fh:
        fh.write(data)


def save_npz_atomic(path: str | os.PathLike, *, compressed: bool = False, **arrays) -> Path:
    """Write ``arrays`` to the NPZ file ``path`` atomically (``numpy.savez``, or
    ``numpy.savez_compressed`` when ``compressed``); returns the path."""
    import numpy as np

    with open_atomic(path, "wb") as fh:
        (np.savez_compressed if compressed else np.savez)(fh, **arrays)
    return Path(path)


def save_figure(fig, path: str | os.PathLike, **kwargs) -> Path:
    """``fig.savefig(path, **kwargs)`` (matplotlib) atomically; returns the path."""
    with atomic_path(path, keep_suffix=True) as tmp:
        fig.savefig(tmp, **kwargs)
    return Path(path)


def read_npz(path: str | os.PathLike) -> dict:
    """Every array of the NPZ file ``path`` (no pickles), read in full.

    A file that is not a complete NPZ file (truncated, not a zip, a damaged member) raises
    ValueError saying so; OSError (missing, no permission) passes through unchanged.
    """
    import struct
    import zipfile
    import zlib

    import numpy as np

    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except OSError:
        raise
    except (zipfile.BadZipFile, zlib.error, EOFError, ValueError, KeyError, struct.error,
            NotImplementedError) as exc:
        raise ValueError(f"{Path(path).name} is not a complete NPZ file (truncated or damaged: "
                         f"{type(exc).__name__}: {exc})") from None


def check_output_path(path: str | None, option: str, suffixes: tuple[str, ...] | None = None) -> None:
    """Refuse an output path before any work is done: a wrong file type, a folder, or a folder
    that cannot be created or written (InputError naming the option)."""
    if not path:
        return
    p = Path(path)
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise InputError(f"{option}: cannot write {p.suffix or 'a file without extension'!r} files "
                         f"({p.name}); use one of {', '.join(suffixes)}")
    if p.is_dir():
        raise InputError(f"{option}: {p} is a folder, not a file")
    if p.exists() and not os.access(p, os.W_OK):
        raise InputError(f"{option}: {p} is not writable")
    parent = p.parent
    while not parent.exists():            # the first existing folder must be writable
        if parent == parent.parent:
            break
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{option}: cannot create a folder for {p}: {parent} is a file")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{option}: cannot write into {parent}")
