"""Running a study of studies/ in its ``--quick`` mode from a test, and the checks of its sidecar.

Shared by tests/studies and the validation tests that run a study (``from _studies import run_study``).
"""
from __future__ import annotations

import importlib.metadata
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

from _paths import ROOT, STUDIES


def load_study(name: str):
    """The module of ``studies/<name>.py``, imported from its file (studies are scripts, not a
    package), to test its functions directly."""
    spec = importlib.util.spec_from_file_location(f"study_{name}", STUDIES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def run_study(name: str, out: Path, *args: str, timeout: float = 300.0, env: dict | None = None) -> Path:
    """``python studies/<name>.py --quick --out OUT *args`` from the repository root; asserts exit 0
    and the sidecar, returns OUT."""
    e = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg", **(env or {}))
    r = subprocess.run([sys.executable, str(STUDIES / f"{name}.py"), "--quick", "--out", str(out), *args],
                       cwd=ROOT, capture_output=True, text=True, timeout=timeout, env=e)
    assert r.returncode == 0, f"{name} --quick failed:\n{r.stdout[-2000:]}\n{r.stderr[-3000:]}"
    check_sidecar(out, name)
    return out


def check_sidecar(out: Path, name: str) -> dict:
    """run.json: script, the quick flag, the commit (40 hex digits in a git checkout) with its
    dirty flag, and the versions of the installed packages."""
    side = json.loads((out / "run.json").read_text())
    assert side["script"] == f"studies/{name}.py"
    assert side["args"]["quick"] is True and Path(side["args"]["out"]) == out
    if (ROOT / ".git").exists():
        assert len(side["commit"]) == 40 and all(c in "0123456789abcdef" for c in side["commit"])
        assert isinstance(side["dirty"], bool)
    v = side["versions"]
    for pkg in ("numpy", "scipy", "scikit-fem", "gmsh", "meshio", "conformal"):
        assert v[pkg] == importlib.metadata.version(pkg), pkg
    assert v["python"] == ".".join(map(str, sys.version_info[:3]))
    assert side["machine"]["cpu_count"] == os.cpu_count() and side["date"].startswith("20")
    return side
