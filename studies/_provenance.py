"""The sidecar of a study run: ``run.json`` next to the outputs, recording what produced them.

Every study in ``studies/`` calls :func:`write_sidecar` once its outputs are written, so that each
committed output can be traced to the script, its arguments, the commit of the tree (with a
``dirty`` flag when the working tree had uncommitted changes) and the package versions.

Import from a study (works with ``python studies/x.py`` from any directory and with
``runpy.run_path``)::

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from _provenance import output_dir, write_sidecar  # noqa: E402

    out = output_dir("x", args)      # --out, else studies/out/x (full) or a temporary folder (--quick)
    ...
    write_sidecar(out, __file__, args, extra={"summary": ...})
"""
from __future__ import annotations

import argparse
import datetime
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: distributions whose versions are recorded (installed name, as pip knows it)
PACKAGES = ("numpy", "scipy", "scikit-fem", "gmsh", "meshio", "pyvista", "matplotlib", "conformal")


def _git(*args: str) -> str:
    try:
        r = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return ""
    return r.stdout if r.returncode == 0 else ""


def git_state() -> dict:
    """The commit of the tree (``""`` outside git) and whether tracked files differ from it.

    ``dirty`` looks at tracked files only (``git status --porcelain --untracked-files=no``):
    untracked study outputs being written do not make a run dirty.
    """
    commit = _git("rev-parse", "HEAD").strip()
    lines = [line for line in _git("status", "--porcelain", "--untracked-files=no").splitlines() if line.strip()]
    return {"commit": commit, "dirty": bool(lines) if commit else None,
            "dirty_files": sorted(line[3:] for line in lines)}


def _in_tree(value):
    """A path argument inside the repository, relative to its root (other values unchanged)."""
    if isinstance(value, (str, Path)) and Path(value).is_absolute():
        try:
            return Path(value).resolve().relative_to(ROOT).as_posix()
        except ValueError:
            return str(value)
    return value


def versions() -> dict:
    """Python and package versions (``None`` for a package that is not installed)."""
    out = {"python": platform.python_version()}
    for name in PACKAGES:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = None
    return out


def output_dir(name: str, args: argparse.Namespace) -> Path:
    """The output folder of a study run, created: ``args.out`` when given, else
    ``studies/out/<name>`` for a full run and ``<tmp>/conformal_studies_quick/<name>`` for a
    ``--quick`` one (a quick run never overwrites the committed full outputs).  Sets ``args.out``
    to the folder, so that the sidecar records it."""
    if getattr(args, "out", None):
        out = Path(args.out)
    elif getattr(args, "quick", False):
        out = Path(tempfile.gettempdir()) / "conformal_studies_quick" / name
    else:
        out = ROOT / "studies" / "out" / name
    out.mkdir(parents=True, exist_ok=True)
    args.out = str(out)
    return out


def write_sidecar(out_dir, script, args=None, extra: dict | None = None) -> Path:
    """Write ``out_dir/run.json`` and return its path.

    Parameters
    ----------
    out_dir : str or Path
        The study's output folder (created if missing).
    script : str or Path
        The study script (``__file__``); recorded relative to the repository root.
    args : argparse.Namespace or dict or None
        The parsed arguments of the run.
    extra : dict, optional
        More keys for the sidecar (e.g. a summary of the results); they may not replace the
        standard ones.

    Returns
    -------
    Path
        The path of ``run.json``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = Path(script).resolve()
    try:
        rel = path.relative_to(ROOT).as_posix()
    except ValueError:
        rel = str(path)
    if isinstance(args, argparse.Namespace):
        args = vars(args)
    args = {k: _in_tree(v) for k, v in (args or {}).items()}
    git = git_state()
    record = {
        "script": rel,
        "args": args,
        "argv": sys.argv[1:],
        "commit": git["commit"],
        "dirty": git["dirty"],
        "dirty_files": git["dirty_files"],
        "versions": {**versions(), "commit": git["commit"]},
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": {"cpu_count": os.cpu_count(), "platform": platform.platform(),
                    "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None},
    }
    for key, value in (extra or {}).items():
        if key in record:
            raise ValueError(f"write_sidecar: extra key {key!r} is a standard key")
        record[key] = value
    target = out / "run.json"
    target.write_text(json.dumps(record, indent=2, default=str) + "\n", encoding="utf-8")
    return target
