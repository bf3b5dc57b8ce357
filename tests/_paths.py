"""Paths and reference data shared by every test (tests/unit, tests/validation, tests/studies).

Importable from any test module (``from _paths import ROOT, REFERENCE``): tests/ is on ``sys.path``
(pyproject.toml ``[tool.pytest.ini_options] pythonpath``).  No test computes a path from its own
``__file__``, so a test file can move between the folders without change.
"""
from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

import conformal

#: the repository root
ROOT = Path(__file__).resolve().parents[1]
#: the tests' reference data (CONTACT's outputs, decks, stored values; tests/reference/README files)
REFERENCE = ROOT / "tests" / "reference"
#: CONTACT's outputs of the standard cases
CONTACT_CASES = REFERENCE / "contact_cases.json"
#: CONTACT's public input decks with their reference outputs
DECKS = REFERENCE / "contact_decks"
#: the example scenes
SCENES = ROOT / "meshes" / "scenes"
#: the study scripts
STUDIES = ROOT / "studies"
#: the packaged profiles
PROFILES = Path(conformal.__file__).parent / "data" / "profiles"
#: the built-in demo scene
DEMO = ROOT / "conformal" / "data" / "scenes" / "demo.toml"


@lru_cache(maxsize=1)
def _contact_cases() -> dict:
    return json.loads(CONTACT_CASES.read_text(encoding="utf-8"))["cases"]


def reference_cases() -> dict:
    """CONTACT's reference cases by name (parsed once; do not modify the returned mapping)."""
    return _contact_cases()
