"""``conformal inp`` on a module-1 deck: its cases form a sequence of wheelset positions, each
started from the one before (conformal.contact_inp.deck.solve_deck, WarmStart), and the deck loads
none of the module-3 solver path (conformal.contact_inp.solve3, conformal.solvers.history).

The deck is the first three cases of Manchester A-2.2 (right wheel, y_ws 0, 0.5, 1.0 mm) with
0.8 mm elements instead of 0.2 mm, so that it solves in a few seconds.
"""
from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from conformal.contact_inp.deck import read_deck, solve_deck
from _paths import DECKS, ROOT

#: N: a warm-started case against the same case solved alone, on the coarse deck (measured: FN, FX,
#: FY within 0.029 N; the 0.2 mm deck of 21 cases within 0.41 N = 4e-5 of the 10 kN wheel load, as
#: the study's warm-started sequence: the balance's tolerances, solve1.solve_case)
WARM_TOL = 0.2


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


def test_module1_sequence_starts_each_case_from_the_one_before(short_deck, monkeypatch):
    """The cases 2 and 3 start from their predecessor's WarmStart; each agrees with the same case
    solved alone (``--cases N``: cold) to the balance's tolerance and is balanced."""
    import conformal.contact_inp.solve1 as solve1

    seen = []
    solve_case = solve1.solve_case

    def spy(case, raw, base_dir, warm=None):
        seen.append(warm)
        return solve_case(case, raw, base_dir, warm=warm)

    monkeypatch.setattr(solve1, "solve_case", spy)
    parsed = read_deck(short_deck)
    warm = list(solve_deck(parsed))
    assert [d["case"] for d in warm] == [1, 2, 3]
    assert seen[0] is None and all(w is not None and w.lowering > 0 for w in seen[1:])
    seen.clear()
    for d in warm:
        cold = list(solve_deck(parsed, cases=[d["case"]]))[0]
        for key in ("FN", "FX", "FY"):
            assert d[key] == pytest.approx(cold[key], abs=WARM_TOL), (d["case"], key)
        assert d["FZ_track"] == pytest.approx(10000.0, rel=1e-5) and d["converged"]
    assert seen == [None, None, None]       # a case solved alone starts cold


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
