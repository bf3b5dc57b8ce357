"""The Python API: conformal.solve / load_scene on a path, a dict or a scene with overrides,
Scene.with_, Result.to_dict / plot / plot3d, and no global state changed by library code."""
import json
import os
import subprocess
import sys

import pytest

import conformal
from conformal.errors import InputError

from _paths import DEMO, SCENES

CIRCLE = {"material": {"G": 82000.0, "nu": 0.28}, "friction": {"mu": 0.3},
          "geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3}, "load": {"normal_force": 1e4},
          "kinematics": {"xi": 1e-3}, "grid": {"n": 16}, "model": {"theory": "hertz"}}


def test_solve_a_path_a_dict_and_a_scene_with_overrides():
    r = conformal.solve(SCENES / "flange_s1002_uic60.toml")
    assert r.theory == "conformal" and r.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-4)
    a = conformal.solve(CIRCLE)
    # Hertz's closed form (independent): a = (3 F R / (4 E*))^(1/3) with R = 1/(2A) = 500 mm and the
    # contact modulus of two steel bodies E* = E / (2 (1 - nu²)) = G / (1 - nu)
    E_star = 82000.0 / (1 - 0.28)
    radius = (3 * 1e4 * 500.0 / (4 * E_star)) ** (1 / 3)
    assert a.a == pytest.approx(radius, rel=1e-9)
    b = conformal.solve(CIRCLE, model__theory="exact")
    s = conformal.load_scene(CIRCLE).with_("model.theory", "exact")
    c = conformal.solve(s)
    assert b.theory == c.theory == "exact" and b.FX == pytest.approx(c.FX, rel=1e-12) and b.FX < 0
    assert conformal.solve(s, kinematics__xi=0.0).FX == pytest.approx(0.0, abs=1e-6 * b.FN)


def test_scene_with_changes_one_key_and_validates():
    s = conformal.load_scene(DEMO)
    t = s.with_("geometry.lateral_shift", 5.0)
    assert t.geometry.lateral_shift == 5.0 and s.geometry.lateral_shift == 6.2     # frozen original
    assert t.geometry.wheel_profile == s.geometry.wheel_profile
    assert s.with_(model__maxout=3).model.options["maxout"] == 3
    with pytest.raises(InputError, match="did you mean 'theory'"):
        s.with_("model.thoery", "exact")
    with pytest.raises(InputError, match=r"\[geometry\] yaw"):
        s.with_(geometry__yaw=2.0)
    with pytest.raises(InputError, match="unknown section"):
        conformal.solve(CIRCLE, modle__theory="exact")


def test_to_dict_is_the_json_summary():
    r = conformal.solve(CIRCLE, model__theory="fastsim")
    d = r.to_dict()
    assert d == r.summary() and json.loads(json.dumps(d)) == d
    assert d["FS"] == d["FY"] and d["warnings"] == [] and d["theory"] == "fastsim"


def test_plot_draws_into_the_given_axes_with_colour_bars_from_zero():
    from matplotlib.figure import Figure

    r = conformal.solve(CIRCLE, model__theory="exact")
    fig = Figure()
    ax = fig.subplots()
    assert r.plot(ax) is ax
    mesh = ax.collections[0]
    assert mesh.norm.vmin == 0.0 and mesh.norm.vmax == pytest.approx(r.pmax)
    assert "N/mm²" in ax.get_title() and ax.get_xlabel() == "x (rolling) [mm]"
    ax2 = r.plot(fig.subplots(), quantity="pt")
    assert "FX" in ax2.get_title() and " N" in ax2.get_title()
    hz = conformal.solve(CIRCLE)           # no field: the Hertz ellipse
    assert "Hertz" in hz.plot(Figure().subplots()).get_title()


def test_plot3d_takes_a_plotter():
    pv = pytest.importorskip("pyvista")
    r = conformal.solve(DEMO, grid__n=12)
    pl = pv.Plotter(off_screen=True)
    assert r.plot3d(pl) is pl
    assert len(pl.renderer.actors) >= 4               # rail, wheel, strip, contact (+ arrows, lines)
    pl.close()
    flat = conformal.solve(CIRCLE, model__theory="exact")
    pl = flat.plot3d()
    meshes = [a for name, a in pl.renderer.actors.items() if name.startswith("StructuredGrid")]
    assert len(meshes) == 1
    assert tuple(meshes[0].mapper.scalar_range) == pytest.approx((0.0, float(flat.field.pn.max())))
    pl.close()


@pytest.mark.slow
def test_library_code_changes_no_global_state(tmp_path):
    import matplotlib
    import pyvista as pv
    from threadpoolctl import threadpool_info

    from conformal.plots import plot_result

    backend, off, env = matplotlib.get_backend(), pv.OFF_SCREEN, dict(os.environ)
    threads = [p["num_threads"] for p in threadpool_info()]
    r = conformal.solve(DEMO, grid__n=12)
    plot_result(r, tmp_path / "d.png")
    plot_result(conformal.solve(CIRCLE, model__theory="exact"), tmp_path / "c.png")
    assert matplotlib.get_backend() == backend and pv.OFF_SCREEN == off and dict(os.environ) == env
    assert [p["num_threads"] for p in threadpool_info()] == threads


@pytest.mark.slow
def test_no_x_server_warning_from_a_3d_plot(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    p = subprocess.run([sys.executable, "-m", "conformal.cli", "solve", str(DEMO), "--plot", str(tmp_path / "d.png")],
                       capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0 and (tmp_path / "d.png").stat().st_size > 10_000
    assert "X server" not in p.stderr and "vtk" not in p.stderr.lower()


def test_a_single_threaded_blas_inside_a_solve(monkeypatch):
    from threadpoolctl import threadpool_info

    from conformal import models

    seen = []
    real = models.solve_problem

    def spy(problem):
        seen.extend(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")
        return real(problem)

    for k in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS"):
        monkeypatch.delenv(k, raising=False)
    monkeypatch.setattr("conformal.dispatch.solve_problem", spy)
    conformal.solve(CIRCLE, model__theory="fastsim")
    assert seen and all(n == 1 for n in seen)


def test_nested_single_threaded_blas_limits_once_and_restores(monkeypatch):
    """A command that wraps many solves sets the limit once; the solves inside do not set it again
    (each limit rescans the loaded libraries), and leaving the outer block restores BLAS."""
    import threadpoolctl
    from threadpoolctl import threadpool_info

    from conformal._threads import single_threaded_blas

    for k in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS"):
        monkeypatch.delenv(k, raising=False)
    calls = []
    real = threadpoolctl.threadpool_limits

    def counting(*a, **k):
        calls.append(k)
        return real(*a, **k)

    monkeypatch.setattr(threadpoolctl, "threadpool_limits", counting)
    before = [p["num_threads"] for p in threadpool_info()]
    with single_threaded_blas():
        for _ in range(3):
            with single_threaded_blas():
                inner = [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]
                assert all(n == 1 for n in inner)
    assert len(calls) == 1
    assert [p["num_threads"] for p in threadpool_info()] == before
    with single_threaded_blas():            # a new outer block limits again
        pass
    assert len(calls) == 2


@pytest.mark.parametrize("name", ["circ.toml", "flange_worn.toml", "mbench_right_y5.toml", "groove_conformal.toml"])
def test_scene_to_dict_round_trip(name):
    from conformal.scene import scene_from_dict

    s = conformal.load_scene(SCENES / name)
    assert scene_from_dict(s.to_dict(), base_dir=s.base_dir, name=s.name) == s


def test_with_revalidates_every_key():
    s = conformal.load_scene(SCENES / "circ.toml")
    with pytest.raises(InputError, match=r"\[geometry\] A: must be > 0"):
        s.with_(geometry__A=-1.0)
    with pytest.raises(InputError, match=r"\[friction\] mu"):
        s.with_(friction__mu_kinetic=0.0)
    t = s.with_("load.approach", 0.05)
    assert t.load.approach == 0.05 and t.load.normal_force is None
