"""The example gallery (examples/*.py, shown in the documentation) runs as it is shown.

Each script runs in its own process (as a user runs it), writes its figures off-screen into a
temporary folder and prints one JSON line; the test checks the printed numbers against the
independent value the example names (Hertz, Cattaneo, the Manchester benchmark's contact jump, the
vertical balance), and that the script draws exactly the figures docs/examples.md shows under its
heading (kept in docs/_static/gallery), at their size.  Scripts that take more than about 5 s are
in the slow lane.
"""
import json
import os
import re
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from _paths import ROOT

EXAMPLES = ROOT / "examples"
PAGE = ROOT / "docs" / "examples.md"
GALLERY = ROOT / "docs" / "_static" / "gallery"


def run_example(name: str, tmp_path: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg", OMP_NUM_THREADS="1",
               CONFORMAL_CACHE=str(tmp_path / "cache"))
    proc = subprocess.run([sys.executable, str(EXAMPLES / name), str(tmp_path / "out")], env=env,
                          capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def assert_png(path: Path, min_bytes: int = 5000) -> None:
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", path
    assert path.stat().st_size > min_bytes, f"{path} is nearly empty"


def png_size(path: Path) -> tuple[int, int]:
    """Width and height in pixels (the PNG header's IHDR chunk)."""
    head = path.read_bytes()[:24]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", path
    return struct.unpack(">II", head[16:24])


def documented_figures() -> dict[str, list[str]]:
    """docs/examples.md: the gallery figures shown under each script's heading, {script: [png names]}."""
    out, shown = {}, []
    for line in PAGE.read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            shown = []
        if m := re.match(r"!\[[^]]*\]\(_static/gallery/([^)]+)\)", line):
            shown.append(m.group(1))
        if m := re.match(r"```\{literalinclude\} \.\./examples/(\S+\.py)", line):
            out[m.group(1)] = shown
    return out


def assert_gallery(name: str, out: Path) -> None:
    """The script ``name`` drew into ``out`` exactly the figures its gallery section shows, each the
    size of the committed one (docs/_static/gallery)."""
    shown = documented_figures()[name]
    assert sorted(p.name for p in out.glob("*.png")) == sorted(shown)
    for fig in shown:
        assert_png(out / fig)
        assert png_size(out / fig) == png_size(GALLERY / fig), (
            f"{fig}: the gallery's copy is stale; draw it again with python examples/{name} docs/_static/gallery")


def test_every_example_is_tested():
    tested = {"hertz_circle.py", "load_history.py", "flange_contact.py", "wheelset_geometry.py", "fe_influence.py"}
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested


def test_the_gallery_shows_every_example_with_its_committed_figures():
    shown = documented_figures()
    assert set(shown) == {p.name for p in EXAMPLES.glob("*.py")}
    assert all(shown.values()), {k: v for k, v in shown.items() if not v}
    figures = [f for v in shown.values() for f in v]
    assert len(figures) == len(set(figures)) and set(figures) == {p.name for p in GALLERY.glob("*")}
    for fig in figures:
        assert_png(GALLERY / fig)
        assert 200 <= min(png_size(GALLERY / fig)) and max(png_size(GALLERY / fig)) <= 1200, fig   # readable, small
    with pytest.raises(AssertionError):            # the parser sees a figure missing from a section
        assert_gallery("hertz_circle.py", GALLERY / "nowhere")


def test_hertz_circle(tmp_path):
    d = run_example("hertz_circle.py", tmp_path)
    assert d["converged"]
    assert d["pmax_exact"] == pytest.approx(d["p0_hertz"], rel=0.005)      # 40 x 40 grid: 0.06 %
    # the computed patch is resolved to about one element (2.2 a / 40) of Hertz's radius
    assert d["a_exact"] == pytest.approx(d["a_hertz"], abs=2.2 * d["a_hertz"] / 40)
    assert d["FX_exact"] < 0 and d["FX_fastsim"] < 0                       # xi > 0 gives FX < 0
    assert_gallery("hertz_circle.py", tmp_path / "out")


def test_load_history_follows_cattaneo(tmp_path):
    d = run_example("load_history.py", tmp_path)
    for s in d["steps"]:
        assert s["shift"] == pytest.approx(s["shift_cattaneo"], rel=0.005)
        assert s["c_over_a"] == pytest.approx(s["c_over_a_cattaneo"], rel=0.03)
    assert_gallery("load_history.py", tmp_path / "out")


@pytest.mark.slow
def test_flange_contact_balances_the_wheel_load(tmp_path):
    d = run_example("flange_contact.py", tmp_path)
    assert d["FZ_track"] == pytest.approx(10000.0, rel=1e-4)                # the scene's wheel_load
    lo, hi = sorted(d["contact_angle_range_deg"])
    assert -50 < lo < hi < -15                                              # flange root: a conformal patch
    assert hi - lo > 10
    assert_png(tmp_path / "out" / "flange_3d.png", 20000)
    assert_gallery("flange_contact.py", tmp_path / "out")


@pytest.mark.slow
def test_wheelset_geometry_jumps_to_the_gauge_corner(tmp_path):
    d = run_example("wheelset_geometry.py", tmp_path)
    angle = dict(zip(d["shift"], d["contact_angle_right_deg"]))
    # Manchester A-2.2 (CONTACT): tread contact up to 4.5 mm, gauge corner from 5.0 mm
    assert angle[4.5] > -10 and angle[5.0] < -10
    assert abs(d["delta_r"][0]) < 1e-9                                      # centred: equal radii
    assert_gallery("wheelset_geometry.py", tmp_path / "out")


@pytest.mark.slow
def test_fe_influence_numbers_give_hertz(tmp_path):
    d = run_example("fe_influence.py", tmp_path)
    assert d["FN_fe"] == pytest.approx(d["FN_hertz"], rel=0.005)
    assert d["FN_halfspace"] == pytest.approx(d["FN_hertz"], rel=0.005)
    assert d["pmax_fe"] == pytest.approx(d["pmax_hertz"], rel=0.02)
    assert_gallery("fe_influence.py", tmp_path / "out")
