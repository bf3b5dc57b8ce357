"""Shared fixtures for every test (tests/unit, tests/validation, tests/studies).

Paths (ROOT, REFERENCE, SCENES, ...) and the reference loader are importable constants of
tests/_paths.py; shared scene builders are in tests/_scenes.py.  The reference data (CONTACT's
outputs of the standard cases, tests/reference/contact_cases.json) is parsed once per session
(:func:`_paths.reference_cases`), whichever test module asks first.
"""
from __future__ import annotations

import pytest

from _paths import CONTACT_CASES, DEMO, reference_cases
from _scenes import SWEEP_SCENE


@pytest.fixture(scope="session")
def contact_cases() -> dict:
    """CONTACT's reference cases (tests/reference/contact_cases.json), parsed once."""
    if not CONTACT_CASES.is_file():
        pytest.skip("reference data not available")
    return reference_cases()


@pytest.fixture(scope="session")
def demo_scene():
    """The built-in demo scene (conformal flange-root contact), loaded once."""
    from conformal.scene import load_scene

    return load_scene(DEMO)


@pytest.fixture
def quadratic_scene():
    """Factory of a small Hertzian scene: ``quadratic_scene(theory="exact", n=20, xi=1e-3, ...)``
    (kinematics keys go to [kinematics], grid keys n, scale to [grid])."""
    from conformal.scene import scene_from_dict

    def make(theory: str = "exact", *, A: float = 1e-3, B: float = 1e-3, normal_force: float = 1e4,
             n: int = 20, scale: float = 1.1, mu: float = 0.3, **kinematics):
        return scene_from_dict({"material": {"G": 82000.0, "nu": 0.28}, "friction": {"mu": mu},
                                "geometry": {"kind": "quadratic", "A": A, "B": B},
                                "load": {"normal_force": normal_force}, "kinematics": kinematics,
                                "grid": {"n": n, "scale": scale}, "model": {"theory": theory}})

    return make


@pytest.fixture
def scene_file(tmp_path):
    """A small wheel-rail scene file (S1002/UIC60, 6 x 6 strip, small FE bodies) for precompute."""
    p = tmp_path / "sweep.toml"
    p.write_text(SWEEP_SCENE)
    return p
