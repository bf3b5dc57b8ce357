"""Cache of FE influence numbers: NPZ files keyed by a hash of every input (written atomically, verified on load).

The key is the SHA-256 of a canonical JSON text of everything that changes the numbers (profile
arrays, placement, grid, mesh parameters, material, element order, method, and the influence
code's version ``FE_VERSION``).  Each file ``<key>.npz`` holds the arrays and a ``__meta__`` JSON
text: the key inputs themselves, the key, a SHA-256 of every array's bytes, the creation time and
the statistics of the computation.  On load the key, the inputs and the checksums are verified;
a corrupt, truncated or foreign file is reported with a warning, never used, moved aside to
``<key>.npz.corrupt`` (for inspection) and recomputed; a file that cannot be opened (another
user's file without read permission) is reported and left where it is.  A check that must not
change anything (``precompute --dry-run``) only reports.  Files are written to a temporary name
in the same folder and renamed (:mod:`conformal.files`: atomic, mode 0666 less the umask, so a
cache shared by a group of users or Dask workers is readable by all of them), so an interrupted
job leaves no half-written entry.

``cache clear`` removes only what it can identify as its own: files named ``<64 hex>.npz`` whose
metadata names this format and that key, entries it moved aside, and its own temporary files
older than an hour (a younger one may belong to a job that is writing it now).  Anything else in
the folder (another program's ``results.npz``, an entry it cannot read) is left and counted.

Folder: ``$CONFORMAL_CACHE`` when set, else the per-user cache folder
(``$XDG_CACHE_HOME/conformal`` or ``~/.cache/conformal`` on Linux, ``~/Library/Caches/conformal``
on macOS, ``%LOCALAPPDATA%/conformal/Cache`` on Windows).

>>> import numpy as np, tempfile
>>> c = Cache(tempfile.mkdtemp())
>>> key = c.key({"what": "example", "n": 3})
>>> _ = c.store(key, {"what": "example", "n": 3}, {"kernel": np.arange(4.0)})
>>> c.load(key, {"what": "example", "n": 3})["kernel"].tolist()
[0.0, 1.0, 2.0, 3.0]
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import re
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from conformal.errors import ConformalError
from conformal.files import is_temporary, read_npz, save_npz_atomic

ENV = "CONFORMAL_CACHE"
SUFFIX = ".npz"
META = "__meta__"
FORMAT = "conformal-influence-cache/1"
CORRUPT = ".corrupt"
_NAME = re.compile(r"^[0-9a-f]{64}\.npz$")
#: a temporary file younger than this may be written right now by a running job
TEMP_AGE_S = 3600.0


class CacheWarning(UserWarning):
    """A cache file was unusable (corrupt or foreign) and is recomputed."""


class CacheWriteError(ConformalError):
    """A computed entry could not be written to the cache (full disk, no permission)."""


def default_dir() -> Path:
    """The cache folder: $CONFORMAL_CACHE, else the platform's per-user cache folder."""
    env = os.environ.get(ENV)
    if env:
        return Path(env).expanduser()
    home = Path.home()
    if sys.platform == "darwin":
        return home / "Library" / "Caches" / "conformal"
    if os.name == "nt":
        base = os.environ.get("LOCALAPPDATA")
        return (Path(base) if base else home / "AppData" / "Local") / "conformal" / "Cache"
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else home / ".cache") / "conformal"


def _canonical(obj: Any) -> Any:
    """JSON-ready form with exactly reproducible floats (repr, 17 digits) and arrays as lists."""
    if isinstance(obj, Mapping):
        return {str(k): _canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, (list, tuple)):
        return [_canonical(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return {"__array__": list(obj.shape), "dtype": str(obj.dtype),
                "sha256": hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest()}
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return repr(v) if math.isfinite(v) else str(v)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if obj is None or isinstance(obj, (bool, int, str)):
        return obj
    raise TypeError(f"cache key: cannot hash a {type(obj).__name__}")


def canonical_json(inputs: Mapping[str, Any]) -> str:
    return json.dumps(_canonical(inputs), sort_keys=True, separators=(",", ":"))


def _array_digest(arrays: Mapping[str, np.ndarray]) -> dict[str, str]:
    return {k: hashlib.sha256(np.ascontiguousarray(v).tobytes()).hexdigest() for k, v in sorted(arrays.items())}


@dataclass(frozen=True)
class Entry:
    """One cache file, as listed by :meth:`Cache.entries`."""

    key: str
    path: Path
    size: int
    created: float
    summary: str
    ok: bool


class Cache:
    """A folder of NPZ influence files (see the module docstring)."""

    def __init__(self, folder: str | os.PathLike | None = None):
        self.folder = Path(folder) if folder is not None else default_dir()

    # ------------------------------------------------------------------ keys and paths
    @staticmethod
    def key(inputs: Mapping[str, Any]) -> str:
        """SHA-256 (hex) of the canonical JSON of the inputs."""
        return hashlib.sha256(canonical_json(inputs).encode()).hexdigest()

    def path(self, key: str) -> Path:
        return self.folder / f"{key}{SUFFIX}"

    def has(self, key: str) -> bool:
        return self.path(key).is_file()

    # ------------------------------------------------------------------ read / write
    def store(self, key: str, inputs: Mapping[str, Any], arrays: Mapping[str, np.ndarray],
              stats: Mapping[str, Any] | None = None) -> Path:
        """Write arrays + metadata atomically (temporary file in the folder, then rename)."""
        arrays = {k: np.asarray(v) for k, v in arrays.items()}
        if META in arrays:
            raise ValueError(f"array name {META!r} is reserved")
        meta = {"format": FORMAT, "key": key, "inputs": json.loads(canonical_json(inputs)),
                "checksums": _array_digest(arrays), "created": time.time(),
                "stats": json.loads(json.dumps(dict(stats or {}), default=str))}
        save_npz_atomic(self.path(key), **arrays, **{META: np.array(json.dumps(meta))})
        return self.path(key)

    @staticmethod
    def _read(path: Path) -> tuple[dict, dict]:
        """(metadata, arrays) of a cache file; ValueError if it is not a complete cache file,
        OSError if it cannot be opened."""
        z = read_npz(path)
        if META not in z:
            raise ValueError("no metadata")
        try:
            meta = json.loads(str(z.pop(META)))
        except json.JSONDecodeError as exc:
            raise ValueError(f"unreadable metadata ({exc})") from None
        if not isinstance(meta, dict):
            raise ValueError("unreadable metadata")
        return meta, z

    def load(self, key: str, inputs: Mapping[str, Any] | None = None, *, repair: bool = True
             ) -> dict[str, np.ndarray] | None:
        """The arrays stored under ``key``, or None when absent or unusable (warned).

        An unusable file (truncated, corrupt, foreign) is moved aside to ``<key>.npz.corrupt``
        when ``repair`` (else left as it is); a file that cannot be opened is always left.
        """
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            meta, arrays = self._read(path)
        except OSError as exc:
            warnings.warn(f"influence cache: {path} cannot be opened ({exc.strerror or exc}); "
                          "computing without it (the file is left as it is)", CacheWarning, stacklevel=2)
            return None
        except ValueError as exc:
            return self._reject(path, f"cannot be read ({exc})", repair)
        if meta.get("format") != FORMAT or meta.get("key") != key:
            return self._reject(path, "belongs to another key or format", repair)
        if inputs is not None and meta.get("inputs") != json.loads(canonical_json(inputs)):
            return self._reject(path, "was computed for different inputs", repair)
        if meta.get("checksums") != _array_digest(arrays):
            return self._reject(path, "fails its checksum (corrupt)", repair)
        return arrays

    def meta(self, key: str) -> dict | None:
        """The metadata of the entry ``key`` (None when missing or unreadable)."""
        try:
            return self._read(self.path(key))[0]
        except (OSError, ValueError):
            return None

    def _reject(self, path: Path, why: str, repair: bool) -> None:
        if not repair:
            warnings.warn(f"influence cache: {path.name} {why}", CacheWarning, stacklevel=3)
            return None
        aside = path.with_name(path.name + CORRUPT)
        try:
            os.replace(path, aside)
            where = f"moved to {aside.name}"
        except OSError as exc:
            where = f"left in place ({exc.strerror or exc})"
        warnings.warn(f"influence cache: {path.name} {why}; {where}; recomputing", CacheWarning, stacklevel=3)
        return None

    def get_or_compute(self, inputs: Mapping[str, Any],
                       compute: Callable[[], tuple[Mapping[str, np.ndarray], Mapping[str, Any]]],
                       *, strict: bool = False) -> tuple[dict[str, np.ndarray], bool]:
        """Cached arrays for ``inputs``, computing and storing them when missing.

        ``compute()`` returns (arrays, stats).  Returns (arrays, hit).  Nothing is written when
        compute raises.  A failed write (full disk, no permission) is warned about and the arrays
        are returned uncached, or, when ``strict`` (a job whose purpose is to fill the cache),
        raises :class:`CacheWriteError`.
        """
        key = self.key(inputs)
        arrays = self.load(key, inputs)
        if arrays is not None:
            return arrays, True
        arrays, stats = compute()
        arrays = {k: np.asarray(v) for k, v in arrays.items()}
        try:
            self.store(key, inputs, arrays, stats)
        except OSError as exc:
            text = f"influence cache: cannot write {self.path(key)} ({exc.strerror or exc})"
            if strict:
                raise CacheWriteError(text) from None
            warnings.warn(text + "; continuing without caching", CacheWarning, stacklevel=2)
        return arrays, False

    # ------------------------------------------------------------------ maintenance
    def _own(self, p: Path) -> bool:
        """Whether ``p`` is an entry of this cache: its name is a key and its metadata names this
        format and that key."""
        if not _NAME.match(p.name):
            return False
        try:
            meta = self._read(p)[0]
        except (OSError, ValueError):
            return False
        return meta.get("format") == FORMAT and meta.get("key") == p.stem

    def entries(self) -> list[Entry]:
        """Every file of the folder named like a cache entry (``<64 hex>.npz``), newest first
        (``ok`` False: it cannot be read or is not a valid entry)."""
        if not self.folder.is_dir():
            return []
        out = []
        for p in self.folder.glob(f"*{SUFFIX}"):
            if not _NAME.match(p.name):
                continue
            meta = self.meta(p.stem)
            ok = meta is not None and meta.get("format") == FORMAT and meta.get("key") == p.stem
            summary = str(meta.get("stats", {}).get("summary", "")) if ok else "unreadable"
            st = p.stat()
            out.append(Entry(p.stem, p, st.st_size, float(meta.get("created", st.st_mtime)) if ok else st.st_mtime,
                             summary, ok))
        return sorted(out, key=lambda e: -e.created)

    def clear(self) -> tuple[int, list[Path]]:
        """Remove the cache's own files (see the module docstring): its valid entries, the entries it
        moved aside and its temporary files older than ``TEMP_AGE_S``.  Returns (number removed,
        files left: not identifiable as this cache's own, e.g. another program's NPZ files or
        entries that cannot be read)."""
        if not self.folder.is_dir():
            return 0, []
        n, left = 0, []
        now = time.time()
        for p in sorted(self.folder.iterdir()):
            if not p.is_file():
                continue
            if p.name.endswith(CORRUPT) and _NAME.match(p.name[:-len(CORRUPT)]):
                own = True
            elif is_temporary(p.name) and _NAME.match(p.name[1:].split(".npz.", 1)[0] + SUFFIX):
                if now - p.stat().st_mtime < TEMP_AGE_S:
                    continue                       # may be written by a running job: not ours to judge
                own = True
            else:
                own = self._own(p)
            if not own:
                if p.suffix == SUFFIX:
                    left.append(p)
                continue
            try:
                p.unlink()
                n += 1
            except FileNotFoundError:
                pass                               # removed by another process meanwhile
            except OSError as exc:
                raise ConformalError(f"cannot remove {p}: {exc.strerror or exc}") from None
        return n, left
