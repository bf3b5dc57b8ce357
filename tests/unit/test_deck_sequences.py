"""``conformal inp`` on a module-1 deck: the deck loads none of the module-3 solver path
(conformal.contact_inp.solve3, conformal.solvers.history).

The deck is the first three cases of Manchester A-2.2 (right wheel, y_ws 0, 0.5, 1.0 mm) with
0.8 mm elements instead of 0.2 mm, so that it solves in a few seconds.
"""
from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from _paths import DECKS, ROOT

@pytest.fixture(scope="module")
def short_deck(tmp_path_factory):
    folder = tmp_path_factory.mktemp("deck")
    for name in ("MBench_UIC60_v3.prr", "MBench_S1002_v3.prw"):
        shutil.copy(DECKS / name, folder / name)
    text = (DECKS / "mbench_a22_right.inp").read_text(encoding="latin-1")
    blocks = text.split("%  4: Lateral displacement")
    text = blocks[0].replace("  0.200   0.200   1.000   90d", "  0.800   0.800   1.000   90d", 1) + " 0  MODULE\n"
    (folder / "short.inp").write_text(text, encoding="latin-1")
    return folder / "short.inp"


def test_module1_deck_loads_no_module3_solver(short_deck):
    """Solving a module-1 deck through the CLI imports neither conformal.contact_inp.solve3 nor
    conformal.solvers.history (module 3 only).  (scipy.optimize is imported all the same: by
    scipy.interpolate, which the profile splines need.)"""
    code = ("import sys, io, contextlib\n"
            "from conformal.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    assert main(['inp', {str(short_deck)!r}, '--cases', '1']) == 0\n"
            "print(' '.join(m for m in ('conformal.contact_inp.solve3', 'conformal.solvers.history') "
            "if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == ""
