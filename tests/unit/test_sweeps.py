"""Issue 23: the vertical balance with the height as unknown, solved sweeps, a light import."""
import csv
from functools import partial
import json
import subprocess
import sys

import numpy as np
import pytest

from conformal.cases.wheelrail import (BALANCE_TOL, BalanceCounts, WarmStart, balance_height,
                                       balance_height_bracketing, place_scene, solve_wheel_rail)
from conformal.cli import main
from conformal.scene import load_scene
from conformal.dispatch import solve_scene
from _paths import ROOT
from _scenes import MBENCH, mbench_scene

WORN = ROOT / "meshes" / "scenes" / "flange_worn_three_patches.toml"


#: the Manchester pair (tests/_scenes.py): exact theory, 0.4 mm elements
mbench = partial(mbench_scene, theory="exact", element_size=0.4)


@pytest.mark.parametrize("y,theory", [(0.0, "exact"), (3.0, "exact"), (7.0, "exact"), (3.0, "hertz")])
def test_balance_equals_bracketing_search(y, theory):
    """The Newton-like balance (geometry once per trial height, the height from the linearised
    normal problem) finds the height of the bracketing root search on FZ(z) (Brent, xtol 1e-9 mm)
    within 2e-5 mm and the same normal forces within 1e-4 (its z tolerance BALANCE_ZTOL = 1e-4 mm
    moves FN by about 1.5 dz/approach ~ 1e-5 relative), with a few geometry searches instead of
    about 28 (tread, flange)."""
    sc = mbench(y, theory=theory)
    pl = place_scene(sc)
    counts = []
    z, st, fns = balance_height(pl, sc, counts_out=counts)
    z_ref, st_ref, fns_ref = balance_height_bracketing(pl, sc)
    assert abs(z - z_ref) < 2e-5
    assert len(fns) == len(fns_ref)
    np.testing.assert_allclose(fns, fns_ref, rtol=1e-4)
    assert isinstance(counts[0], BalanceCounts) and not counts[0].bracketing
    assert counts[0].searches <= 5


@pytest.mark.slow
def test_balance_three_patches_equals_bracketing_search():
    """Three patches (the worn pair: gauge corner, tread and flange at once, 7.3 / 3.4 / 1.8 kN):
    the secant on the common lowering with the geometry reused gives the bracketing search's
    height and the force of every patch."""
    sc = load_scene(WORN).with_model(theory="exact")
    sc = sc.with_("geometry.element_size", 0.4)
    pl = place_scene(sc)
    counts = []
    z, st, fns = balance_height(pl, sc, counts_out=counts)
    z_ref, _, fns_ref = balance_height_bracketing(pl, sc)
    assert len(fns) == 3 == len(fns_ref)
    assert abs(z - z_ref) < 2e-5
    np.testing.assert_allclose(fns, fns_ref, rtol=1e-4)
    assert not counts[0].bracketing and counts[0].searches <= 4


def test_warm_start_gives_the_same_solve():
    """A warm start from the neighbouring shift ends at the same balance: forces within the
    balance tolerance BALANCE_TOL of the wheel load, with fewer geometry searches."""
    cold = solve_wheel_rail(mbench(3.0))
    warm = solve_wheel_rail(mbench(3.0), warm=WarmStart.from_result(solve_wheel_rail(mbench(2.5))))
    W = 10000.0
    for k in ("FN", "FX", "FY"):
        assert abs(getattr(warm, k) - getattr(cold, k)) <= 3 * BALANCE_TOL * W
    assert abs(warm.extra["FZ_track"] - W) <= BALANCE_TOL * W
    assert warm.extra["balance"]["searches"] <= cold.extra["balance"]["searches"]


@pytest.mark.slow
def test_sweep_solve_equals_per_position_solve(tmp_path):
    """``conformal sweep --solve`` on the Manchester example scene (exact theory, 0.4 mm elements;
    tread at 0 and 3 mm, flange at 7 mm) gives per shift what ``conformal.solve`` gives for that
    shift (the warm starts end within the balance tolerance: 3 BALANCE_TOL of the wheel load on
    forces of 10-18 kN), a CSV with units in its header, the JSON and the PNG."""
    import tomllib

    sc = mbench(0.0)
    scene_file = tmp_path / "scene.toml"
    text = MBENCH.read_text().replace("element_size = 0.2", "element_size = 0.4").replace("yaw = 0.012", "yaw = 0.0")
    scene_file.write_text(text)
    assert tomllib.loads(text)["geometry"]["element_size"] == 0.4
    out = tmp_path / "out"
    assert main(["sweep", str(scene_file), "--shift", "0:7:3.5", "--solve", "--out", str(out)]) == 0
    with (out / "sweep_solved.csv").open() as fh:
        rows = list(csv.reader(fh))
    head = rows[0]
    assert head[:3] == ["shift [mm]", "FN [N]", "FX [N]"] and "phi [1/mm]" in head and "p0_contact_angle [rad]" in head
    data = json.loads((out / "sweep_solved.json").read_text())
    assert data["units"]["FZ_track"] == "N" and len(data["rows"]) == 3
    assert (out / "sweep_solved.png").stat().st_size > 10_000
    base = load_scene(scene_file)
    W = 10000.0
    for row, json_row in zip(rows[1:], data["rows"]):
        y = float(row[0])
        ref = solve_scene(base.with_("geometry.lateral_shift", y))
        got = dict(zip(head, row))
        for key, val in (("FN [N]", ref.FN), ("FX [N]", ref.FX), ("FS [N]", ref.FY),
                         ("FY_track [N]", ref.extra["FY_track"]), ("FZ_track [N]", ref.extra["FZ_track"])):
            assert abs(float(got[key]) - val) <= 3 * BALANCE_TOL * W, (y, key)
        assert abs(float(got["z_ws [mm]"]) - ref.extra["z_ws"]) < 1e-4
        assert abs(float(got["contact_angle [rad]"]) - ref.extra["contact_angle"]) < 1e-5
        assert json_row["FN"] == pytest.approx(float(got["FN [N]"]), rel=1e-8)
    assert sc is not None


def test_sweep_python_table_and_bad_input():
    """conformal.sweep returns the table (arrays per column, units); a non-wheel-rail scene and a
    bad range are refused with the key named."""
    import conformal
    from conformal.errors import InputError

    t = conformal.sweep(MBENCH, shift=[1.0, 2.0], model__theory="hertz")
    assert len(t) == 2 and t.units["FN"] == "N" and t.units["phi"] == "1/mm"
    np.testing.assert_allclose(t["FZ_track"], 10000.0, rtol=2e-4)
    assert t.errors == (None, None)
    with pytest.raises(InputError, match="wheel_rail"):
        conformal.sweep({"geometry": {"kind": "hertz", "a": 6.0, "b": 6.0}, "load": {"normal_force": 1e5}},
                        shift="0:1:1")
    with pytest.raises(InputError, match="--shift"):
        conformal.sweep(MBENCH, shift="3:1:1")


@pytest.mark.parametrize("theory", ["hertz", "fastsim"])
def test_sweep_equals_solve_fast(theory):
    """The same for the fast theories (Hertz patches, FASTSIM): every row of conformal.sweep equals
    the per-position solve within the balance tolerance."""
    import conformal

    shifts = [0.0, 4.0, 7.0]
    t = conformal.sweep(MBENCH, shift=shifts, model__theory=theory)
    for i, y in enumerate(shifts):
        ref = conformal.solve(MBENCH, model__theory=theory, geometry__lateral_shift=y)
        for k, v in (("FN", ref.FN), ("FX", ref.FX), ("FS", ref.FY), ("FY_track", ref.extra["FY_track"])):
            assert abs(t[k][i] - v) <= 3 * BALANCE_TOL * 10000.0, (y, k)
        assert t["contact_angle"][i] == pytest.approx(ref.extra["contact_angle"], abs=1e-5)


def test_sweep_segments_break_at_contact_jumps():
    """The plot's line segments end where the contact jumps (the tread-to-gauge-corner jump of
    S1002 between 4.5 and 5.0 mm: 10.6 mm along the rail), not between neighbours on one tread."""
    import conformal

    t = conformal.sweep(MBENCH, shift=[4.0, 4.5, 5.0, 5.5], model__theory="hertz")
    segs = t.segments(t["p0_y_rail"])
    assert [(s.start, s.stop) for s in segs] == [(0, 2), (2, 4)]


def test_import_is_light():
    """``import conformal`` loads none of the heavy dependencies (they load where used), and the
    command has --version."""
    code = ("import sys, conformal; heavy = ['numpy', 'scipy', 'matplotlib', 'pyvista', 'vtk', 'gmsh', 'skfem', "
            "'dask', 'meshio']; print([m for m in heavy if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
    v = subprocess.run([sys.executable, "-m", "conformal.cli", "--version"], capture_output=True, text=True,
                       cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    import conformal

    assert v.returncode == 0 and v.stdout.strip() == f"conformal {conformal.__version__}"


@pytest.mark.slow
def test_conformal_sweep_equals_per_position_solve():
    """Theory "conformal" (one curved strip, half-space numbers, [grid] n = 20): the sweep (its
    strips built at the planar balance warm-started from the neighbour) gives the per-position
    solve's forces within 3 BALANCE_TOL of the wheel load, and the per-region columns."""
    import conformal

    scene = ROOT / "meshes" / "scenes" / "flange_s1002_uic60.toml"
    shifts = [5.8, 6.2]
    t = conformal.sweep(scene, shift=shifts, grid__n=20)
    assert t.theory == "conformal" and t.errors == (None, None)
    for i, y in enumerate(shifts):
        ref = conformal.solve(scene, grid__n=20, geometry__lateral_shift=y)
        for k, v in (("FN", ref.FN), ("FX", ref.FX), ("FZ_track", ref.extra["FZ_track"]),
                     ("FY_track", ref.extra["FY_track"])):
            assert abs(t[k][i] - v) <= 3 * BALANCE_TOL * 10000.0, (y, k)
        assert t["p0_FN"][i] > 0 and np.isfinite(t["p0_s_rail"][i])
