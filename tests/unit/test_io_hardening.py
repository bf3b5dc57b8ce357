"""Input and output of the command line: every bad input ends with exit 2 and one line naming the
key (and the closest known one), output paths are checked before solving, the JSON survives a
failing plot, physically questionable results carry warnings, Ctrl-C stops a parallel job, and the
reported wheel-rail ``approach`` means what ``[load] approach`` means."""
import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from conformal.cli import main
from conformal.errors import InputError
from conformal.scene import load_scene, scene_from_dict

from test_scene_cli import scene_file
from _paths import DEMO



def run_cli(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def one_line_error(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("conformal: error:"), err
    assert "Traceback" not in err
    return lines[0]


UNKNOWN = [  # (change, key named, suggestion named)
    (('theory = "fastsim"', 'Theory = "exact"'), "[model] Theory: unknown key", "'theory'"),
    (('theory = "fastsim"', 'theory = "fastsim"\ninflunce = "fe"'), "[model] influnce: unknown key", "'influence'"),
    (('theory = "fastsim"', 'thoery = "exact"'), "[model] thoery: unknown key", "'theory'"),
    (("nu = 0.28", "nu = 0.28\nnuu = 0.3"), "[material] nuu: unknown key", "'nu'"),
    (("mu = 0.3", "mu = 0.3\nmu_statc = 0.4"), "[friction] mu_statc: unknown key", "'mu_static'"),
    (("normal_force = 50000.0", "normal_force = 50000.0\nnormal_forse = 1.0"), "[load] normal_forse", "'normal_force'"),
    (("xi = 0.0005", "xi = 0.0005\nXi = 0.001"), "[kinematics] Xi: unknown key", "'xi'"),
    (("n = 30", "n = 30\nscal = 1.2"), "[grid] scal: unknown key", "'scale'"),
    (("A = 0.001", "A = 0.001\nb = 0.001"), "[geometry] b: unknown key", "'B'"),
    (("[grid]", "[gird]"), "[gird]: unknown section", "'grid'"),
]


@pytest.mark.parametrize("change, key, suggestion", UNKNOWN)
def test_unknown_keys_in_every_section_exit_2_with_the_closest_key(tmp_path, capsys, change, key, suggestion):
    code, out, err = run_cli(capsys, "solve", scene_file(tmp_path, replace=change))
    line = one_line_error(err)
    assert code == 2 and out == ""
    assert key in line and f"did you mean {suggestion}" in line


def test_unknown_wheel_rail_geometry_key(tmp_path):
    text = DEMO.read_text().replace("lateral_shift = 6.2", "lateral_shift = 6.2\nlateral_shfit = 1.0")
    f = tmp_path / "wr.toml"
    f.write_text(text)
    with pytest.raises(InputError, match=r"\[geometry\] lateral_shfit: unknown key \(did you mean 'lateral_shift'\?\)"):
        load_scene(f)


BAD = [  # (change to the good scene, text the one-line error must contain)
    (("name = \"circle\"\n[material]\nG = 82000.0\nnu = 0.28", "name = \"circle\"\nmaterial = 5"),
     "[material] must be a table"),
    (("n = 30", "mx = 20000\nmy = 20000\ndx = 0.01\ndy = 0.01"), "[grid] mx: a 20000 x 20000 grid needs about"),
    (("n = 30", "n = 20000"), "[grid] n: a 20000 x 20000 grid needs about"),
    (("name = \"circle\"", "name = 5"), "name: must be a non-empty string"),
]


@pytest.mark.parametrize("change, message", BAD)
def test_bad_input_exit_2_one_line(tmp_path, capsys, change, message):
    t0 = time.perf_counter()
    code, out, err = run_cli(capsys, "solve", scene_file(tmp_path, replace=change))
    assert code == 2 and message in one_line_error(err)
    assert time.perf_counter() - t0 < 5.0          # refused before anything big is allocated


def test_top_level_material_number_is_refused_by_the_api():
    with pytest.raises(InputError, match=r"\[material\] must be a table"):
        scene_from_dict({"material": 5, "geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
                         "load": {"normal_force": 1.0}})


def test_wheel_rail_ranges_name_the_key(tmp_path, capsys):
    for old, new, message in (("lateral_shift = 6.2", "lateral_shift = 6.2\nyaw = 1.0", "[geometry] yaw:"),
                              ("rail_cant = 0.024995", "rail_cant = 1.2", "[geometry] rail_cant:"),
                              ("lateral_shift = 6.2", "lateral_shift = 6.2\nroll = 0.5", "[geometry] roll:")):
        f = tmp_path / "wr.toml"
        f.write_text(DEMO.read_text().replace(old, new))
        code, out, err = run_cli(capsys, "solve", f)
        assert code == 2 and message in one_line_error(err)


@pytest.mark.parametrize("option, name, message", [
    ("--plot", "x.xyz", "--plot: cannot write '.xyz' files"),
    ("--vtu", "x.png", "--vtu: cannot write '.png' files"),
    ("--json", "afolder", "--json: "),
    ("--json", "afile/r.json", "--json: cannot create a folder"),
])
def test_output_paths_are_checked_before_solving(tmp_path, capsys, monkeypatch, option, name, message):
    (tmp_path / "afolder").mkdir()
    (tmp_path / "afile").write_text("x")

    def no_solve(scene):
        raise AssertionError("solved before checking the output path")

    monkeypatch.setattr("conformal.dispatch.solve_scene", no_solve)
    code, out, err = run_cli(capsys, "solve", scene_file(tmp_path), option, tmp_path / name)
    assert code == 2 and message in one_line_error(err)


def test_json_is_written_when_the_plot_fails(tmp_path, capsys, monkeypatch):
    def broken_plot(*args, **kwargs):
        raise RuntimeError("no renderer")

    monkeypatch.setattr("conformal.plots.plot_result", broken_plot)
    js = tmp_path / "r.json"
    code, out, err = run_cli(capsys, "solve", scene_file(tmp_path), "--json", js, "--plot", tmp_path / "r.png")
    assert code == 1 and "--plot" in err and "no renderer" in err and "JSON summary was written" in err
    d = json.loads(js.read_text())
    assert d == json.loads(out) and d["FN"] == pytest.approx(50000.0)


def test_physically_questionable_results_warn(tmp_path, capsys):
    # the linear theory far beyond the friction bound
    f = scene_file(tmp_path, replace=("xi = 0.0005", "xi = 0.05"))
    code, out, err = run_cli(capsys, "solve", f, "--theory", "linear")
    d = json.loads(out)
    assert code == 0 and d["F_over_muFN"] > 10
    assert any("friction bound" in w for w in d["warnings"]) and "conformal: warning:" in err
    # the empirical theory ignores spin
    f = scene_file(tmp_path, replace=("phi = 0.0", "phi = 0.001"))
    code, out, err = run_cli(capsys, "solve", f, "--theory", "empirical")
    d = json.loads(out)
    assert code == 0 and any("ignores the spin" in w for w in d["warnings"]) and "ignores the spin" in err
    # nothing questionable: an empty list
    code, out, err = run_cli(capsys, "solve", scene_file(tmp_path), "--theory", "fastsim")
    assert code == 0 and json.loads(out)["warnings"] == [] and err == ""


def test_a_steep_rail_cant_warns(tmp_path, capsys):
    f = tmp_path / "wr.toml"
    f.write_text(DEMO.read_text().replace("rail_cant = 0.024995", "rail_cant = 0.1")
                 .replace('theory = "conformal"', 'theory = "hertz"'))
    code, out, err = run_cli(capsys, "solve", f)
    d = json.loads(out)
    assert code == 0 and any("rail_cant" in w for w in d["warnings"]) and "rail_cant" in err


@pytest.mark.parametrize("theory, n", [("conformal", 20), ("exact", 20), ("hertz", 40)])
def test_reported_approach_gives_back_the_wheel_load(theory, n):
    """The JSON's ``approach`` of a wheel-load solve is the wheelset's lowering below the height where
    its first wheel touches, as ``[load] approach``: solving at it gives back the same forces."""
    from conformal.dispatch import solve_scene

    sc = load_scene(DEMO).with_(model__theory=theory, grid__n=n)
    r = solve_scene(sc)
    assert r.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-4)
    assert 0.02 < r.approach < 0.05
    r2 = solve_scene(sc.with_("load.approach", r.approach))
    assert r2.approach == pytest.approx(r.approach, rel=1e-12)
    assert r2.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-3)
    assert r2.FN == pytest.approx(r.FN, rel=1e-3)


JOB = textwrap.dedent("""
    import signal, sys, time
    from pathlib import Path
    from conformal.jobs import run_tasks

    # Ctrl-C as in a terminal, also where this test runs in a background job (which starts with
    # SIGINT ignored, and Python then keeps it ignored)
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def slow(task):
        folder, name, t = task
        time.sleep(t)
        Path(folder, name).write_text("done")

    if __name__ == "__main__":
        folder, workers = sys.argv[1], int(sys.argv[2])
        tasks = [(folder, f"item{k}", 0.2 if k < 2 else 60.0) for k in range(6)]
        try:
            run_tasks(slow, tasks, [t[1] for t in tasks], workers=workers, progress=False)
        except KeyboardInterrupt:
            sys.exit(130)
""")


@pytest.mark.parametrize("workers", [1, 2])
def test_ctrl_c_stops_a_parallel_job_within_seconds_keeping_finished_items(tmp_path, workers):
    script = tmp_path / "job.py"
    script.write_text(JOB)
    out = tmp_path / "out"
    out.mkdir()
    p = subprocess.Popen([sys.executable, str(script), str(out), str(workers)], start_new_session=True,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while len(list(out.iterdir())) < 2 and time.time() < deadline:   # the two short items finished
        time.sleep(0.1)
    time.sleep(0.5)
    t0 = time.perf_counter()
    os.killpg(p.pid, signal.SIGINT)                   # Ctrl-C in a terminal: the whole group
    p.communicate(timeout=30)
    assert time.perf_counter() - t0 < 5.0
    assert p.returncode == 130
    assert sorted(f.name for f in out.iterdir()) == ["item0", "item1"]
