"""Precomputation jobs (conformal.jobs) and ``conformal precompute``: sweep parsing, caching of
every position, resumption after an interruption, optional Dask."""
from __future__ import annotations

import sys

import pytest

from conformal.cli import main
from conformal.errors import InputError
from conformal.influence.cache import Cache
from conformal.cases.precompute import plan, precompute
from conformal.jobs import parse_sweep, run
from _paths import SCENES



def test_parse_sweep():
    s = parse_sweep("shift=0:10:0.5")
    assert s.key == "shift" and len(s.values) == 21 and s.values[-1] == 10.0 and s.values[1] == 0.5
    assert parse_sweep("yaw=0.001,0.002").values == (0.001, 0.002)
    for bad, msg in (("shift", "KEY=start"), ("speed=0:1:1", "unknown key"), ("shift=0:1:-1", "does not lead"),
                     ("shift=a:b:c", "cannot read"), ("shift=0:1e9:1e-3", "more than")):
        with pytest.raises(InputError, match=msg):
            parse_sweep(bad)


@pytest.mark.slow
def test_precompute_caches_every_position_and_resumes(scene_file, tmp_path, capsys):
    """Two positions x (rail, wheel) = 4 FE bodies; a second run computes nothing; after losing
    one file (an interrupted job) only that one is redone."""
    cache = tmp_path / "cache"
    assert main(["precompute", str(scene_file), "--sweep", "shift=0:1:1", "--cache", str(cache),
                 "--workers", "1", "--no-progress"]) == 0
    assert "4 computed" in capsys.readouterr().out
    entries = Cache(cache).entries()
    assert len(entries) == 4 and all(e.ok for e in entries)
    k = Cache(cache).load(entries[0].key)["kernel"]
    assert k.ndim == 5 and k.shape[3:] == (3, 3) and k.shape[1] == k.shape[2] == 6
    assert main(["precompute", str(scene_file), "--sweep", "shift=0:1:1", "--cache", str(cache),
                 "--no-progress"]) == 0
    assert "4 already cached, 0 computed" in capsys.readouterr().out
    entries[-1].path.unlink()
    assert main(["precompute", str(scene_file), "--sweep", "shift=0:1:1", "--cache", str(cache),
                 "--no-progress", "--dry-run"]) == 0
    assert "3 already cached" in capsys.readouterr().out
    assert main(["precompute", str(scene_file), "--sweep", "shift=0:1:1", "--cache", str(cache),
                 "--no-progress"]) == 0
    assert "3 already cached, 1 computed" in capsys.readouterr().out


@pytest.mark.slow
def test_interrupted_job_leaves_only_complete_entries(scene_file, tmp_path, monkeypatch):
    """An item interrupted mid-way (KeyboardInterrupt) writes nothing; finished items stay."""
    from conformal import jobs
    from conformal.scene import load_scene

    scene = load_scene(scene_file)
    cache = Cache(tmp_path / "cache")
    items, failed = plan(scene, parse_sweep("shift=0"), cache=cache)
    assert len(items) == 2 and not failed and not any(it.cached for it in items)
    real = jobs.compute_item
    calls = []

    def interrupt_second(item, folder):
        calls.append(item.label)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(item, folder)

    monkeypatch.setattr(jobs, "compute_item", interrupt_second)
    with pytest.raises(KeyboardInterrupt):
        run(items, cache_folder=str(cache.folder), workers=1, progress=False)
    assert len(cache.entries()) == 1 and not list(cache.folder.glob(".*.tmp"))
    items2, _ = plan(scene, parse_sweep("shift=0"), cache=cache)
    assert sum(it.cached for it in items2) == 1


@pytest.mark.slow
def test_dask_missing_is_a_clear_error(scene_file, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)     # import fails as if not installed
    code = main(["precompute", str(scene_file), "--sweep", "shift=0", "--cache", str(tmp_path / "c"),
                 "--scheduler", "local", "--no-progress"])
    assert code == 2
    assert "Dask is not installed" in capsys.readouterr().err


def test_precompute_bad_input(scene_file, tmp_path, capsys):
    assert main(["precompute", str(scene_file), "--sweep", "shift=0:1", "--cache", str(tmp_path)]) == 2
    assert "--sweep" in capsys.readouterr().err
    planar = tmp_path / "planar.toml"
    planar.write_text(scene_file.read_text().replace('kind = "wheel_rail"\nwheel_profile = "S1002"\nrail_profile = "UIC60"\n'
                                    'lateral_shift = 0.0', 'kind = "quadratic"\nA = 0.001\nB = 0.001')
                      .replace("wheel_load", "normal_force"))
    assert main(["precompute", str(planar), "--sweep", "shift=0", "--cache", str(tmp_path)]) == 2
    assert "wheel_rail" in capsys.readouterr().err


@pytest.mark.slow
def test_local_dask_cluster(scene_file, tmp_path):
    import dask.distributed  # noqa: F401 - in the test extra: the Dask path runs in CI, never skipped
    from conformal.scene import load_scene

    rep = precompute(load_scene(scene_file), parse_sweep("shift=0"), cache=tmp_path / "c", workers=1,
                     scheduler="local", progress=False)
    assert rep.done == 2 and not rep.failed
    assert len(Cache(tmp_path / "c").entries()) == 2


@pytest.mark.slow
def test_precompute_fills_the_conformal_strip_of_a_multi_patch_scene(tmp_path, monkeypatch):
    """The worn pair at 9.9 mm has two geometric patches; the conformal theory solves them on
    ONE strip (conformal.cases.conformal.curved_problem_from_wheel_rail).  precompute must plan
    that strip (rail + wheel: 2 bodies, not 2 per patch), and a conformal solve afterwards must
    find both bodies in the cache (the check fails if plan() builds per-patch grids)."""

    from conformal.scene import load_scene
    from conformal.dispatch import solve_scene

    scene = load_scene(SCENES / "flange_worn_three_patches.toml")
    # at 9.93 mm (the scene's shift: three patches) the strip turns past the vertical gauge face
    # and the rail is no FE body (not a graph over y); at 9.9 mm two patches, tread and flange root
    opts = dict(scene.model.options, max_mx=6, max_ms=14, fe_body_size=0.3, fe_h_patch=4.0)
    scene = scene.with_model(influence="fe", options=opts).with_("geometry.lateral_shift", 9.9)
    cache = Cache(tmp_path / "cache")
    sweep = parse_sweep(f"shift={scene.geometry.lateral_shift}")
    items, failed = plan(scene, sweep, cache=cache)
    assert not failed and sorted(it.label.split()[-2] for it in items) == ["rail", "wheel"]
    rep = precompute(scene, sweep, cache=cache, workers=1, progress=False)
    assert rep.done == 2 and not rep.failed
    monkeypatch.setenv("CONFORMAL_CACHE", str(cache.folder))
    r = solve_scene(scene)
    assert r.extra["n_geometric_patches"] == 2
    fe_stats = r.extra["fe"]
    assert set(fe_stats) == {"rail", "wheel"} and all(s.get("cache_hit") for s in fe_stats.values())
