"""Cache of FE influence numbers: NPZ files keyed by a hash of every input (written atomically, verified on load).

The key is the SHA-256 of a canonical JSON text of everything that changes the numbers (profile
arrays, placement, grid, mesh parameters, material, element order, method, and the influence
code's version ``FE_VERSION``).  Each file ``<key>.npz`` holds the arrays and a ``__meta__`` JSON
text: the key inputs themselves, the key, a SHA-256 of every array's bytes, the creation time and
the statistics of the computation.  On load the key, the inputs and the checksums are verified;
a corrupt, truncated or foreign file is reported with a warning, removed and recomputed, never
used.  Files are written to a temporary name in the same folder and renamed (atomic on POSIX and
Windows), so an interrupted job leaves no half-written entry.

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
import sys
import tempfile
import time
import warnings
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from conformal.errors import ConformalError

ENV = "CONFORMAL_CACHE"
SUFFIX = ".npz"
META = "__meta__"
FORMAT = "conformal-influence-cache/1"


class CacheWarning(UserWarning):
    """A cache file was unusable (corrupt or foreign) and is recomputed."""


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
        self.folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{key[:16]}.", suffix=".tmp", dir=self.folder)
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **arrays, **{META: np.array(json.dumps(meta))})
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, self.path(key))
        except BaseException:
            try:
                os.unlink(tmp)
            except OSError:
                pass
            raise
        return self.path(key)

    def _read(self, path: Path) -> tuple[dict, dict]:
        with np.load(path, allow_pickle=False) as z:
            if META not in z.files:
                raise ValueError("no metadata")
            meta = json.loads(str(z[META]))
            arrays = {k: z[k] for k in z.files if k != META}
        return meta, arrays

    def load(self, key: str, inputs: Mapping[str, Any] | None = None) -> dict[str, np.ndarray] | None:
        """The arrays stored under ``key``, or None when absent or unusable (warned, removed)."""
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            meta, arrays = self._read(path)
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError, json.JSONDecodeError) as exc:
            return self._reject(path, f"cannot be read ({type(exc).__name__}: {exc})")
        if meta.get("format") != FORMAT or meta.get("key") != key:
            return self._reject(path, "belongs to another key or format")
        if inputs is not None and meta.get("inputs") != json.loads(canonical_json(inputs)):
            return self._reject(path, "was computed for different inputs")
        if meta.get("checksums") != _array_digest(arrays):
            return self._reject(path, "fails its checksum (corrupt)")
        return arrays

    def meta(self, key: str) -> dict | None:
        try:
            return self._read(self.path(key))[0]
        except Exception:
            return None

    def _reject(self, path: Path, why: str) -> None:
        warnings.warn(f"influence cache: {path.name} {why}; recomputing", CacheWarning, stacklevel=3)
        try:
            path.unlink()
        except OSError:
            pass
        return None

    def get_or_compute(self, inputs: Mapping[str, Any],
                       compute: Callable[[], tuple[Mapping[str, np.ndarray], Mapping[str, Any]]]
                       ) -> tuple[dict[str, np.ndarray], bool]:
        """Cached arrays for ``inputs``, computing and storing them when missing.

        ``compute()`` returns (arrays, stats).  Returns (arrays, hit).  Nothing is written when
        compute raises.
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
            warnings.warn(f"influence cache: cannot write {self.path(key)} ({exc}); continuing "
                          "without caching", CacheWarning, stacklevel=2)
        return arrays, False

    # ------------------------------------------------------------------ maintenance
    def entries(self) -> list[Entry]:
        """Every cache file in the folder, newest first."""
        if not self.folder.is_dir():
            return []
        out = []
        for p in self.folder.glob(f"*{SUFFIX}"):
            meta = self.meta(p.stem)
            ok = meta is not None and meta.get("key") == p.stem
            summary = str(meta.get("stats", {}).get("summary", "")) if ok else "unreadable"
            st = p.stat()
            out.append(Entry(p.stem, p, st.st_size, float(meta.get("created", st.st_mtime)) if ok else st.st_mtime,
                             summary, ok))
        return sorted(out, key=lambda e: -e.created)

    def clear(self) -> int:
        """Remove every cache file (and leftover temporary files); returns the number removed."""
        if not self.folder.is_dir():
            return 0
        n = 0
        for p in list(self.folder.glob(f"*{SUFFIX}")) + list(self.folder.glob(".*.tmp")):
            try:
                p.unlink()
                n += 1
            except OSError as exc:
                raise ConformalError(f"cannot remove {p}: {exc}") from None
        return n
