"""Every example scene shipped in meshes/scenes (and the demo scene) is read by the package's reader,
gives back its own file's values, survives the round trip through ``Scene.to_dict`` and names profiles
that resolve; paths into the old meshes/profiles folder resolve to the package's one copy."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from conformal.dynamics.scene import load_vehicle_scene
from conformal.geometry.profiles import builtin_dir, load_profile, read_points, resolve_profile
from conformal.scene import load_scene, scene_from_dict
from _paths import ROOT, SCENES

#: scene files of conformal.dynamics (a vehicle on a track: [vehicle], [track], [contact], ...)
VEHICLE_SCENES = {"seed_wheelset.toml"}
FILES = sorted(SCENES.glob("*.toml")) + [ROOT / "conformal" / "data" / "scenes" / "demo.toml"]


def test_the_examples_are_there():
    assert len(FILES) >= 20 and all(f.is_file() for f in FILES)


@pytest.mark.parametrize("path", [f for f in FILES if f.name not in VEHICLE_SCENES], ids=lambda p: p.name)
def test_example_scene_loads(path):
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    scene = load_scene(path)
    assert scene.model.theory == data.get("model", {}).get("theory", "fastsim")
    assert scene.geometry.kind == data["geometry"]["kind"]
    for key, value in data["load"].items():
        assert getattr(scene.load, key) == pytest.approx(value), key
    again = scene_from_dict(scene.to_dict(), base_dir=scene.base_dir, name=scene.name)
    assert again == scene
    if scene.geometry.kind == "wheel_rail":
        for spec in (scene.geometry.wheel_profile, scene.geometry.rail_profile):
            assert resolve_profile(spec, scene.base_dir)[0].is_file()


@pytest.mark.parametrize("name", sorted(VEHICLE_SCENES))
def test_vehicle_scene_loads(name):
    path = SCENES / name
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    scene = load_vehicle_scene(path)
    assert set(data) >= {"vehicle", "track", "contact"} and scene is not None


def test_old_profile_paths_resolve_to_the_package_copy():
    """The profiles once lay in meshes/profiles as well: a scene naming them there keeps working."""
    old = load_profile("../profiles/s1002_analytic.csv", "wheel", base_dir=SCENES)
    assert not (SCENES.parent / "profiles" / "s1002_analytic.csv").exists()
    np.testing.assert_array_equal(old.points, read_points(builtin_dir() / "s1002_analytic.csv"))
    assert Path(old.source) == builtin_dir() / "s1002_analytic.csv"
