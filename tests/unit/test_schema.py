"""The result schema (conformal.schema): every field the models write is documented with its unit."""
from __future__ import annotations


import pytest

import conformal
from conformal.schema import EXTRA, SUMMARY, markdown
from _paths import DEMO

QUADRATIC = {"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1.2e-3}, "load": {"normal_force": 1e4},
             "kinematics": {"xi": 1e-3, "eta": 5e-4, "phi": 1e-4}, "grid": {"n": 12}}


def _undocumented(summary: dict) -> set[str]:
    out = {k for k in summary if k not in SUMMARY and k not in EXTRA}
    for p in summary.get("patches", []):
        out |= _undocumented(p)
    return out


@pytest.mark.parametrize("theory", ["hertz", "linear", "empirical", "johnson_vermeulen", "fastsim", "exact",
                                    "conformal"])
def test_planar_results_carry_documented_fields_only(theory):
    r = conformal.solve(QUADRATIC, model__theory=theory)
    summary = r.summary()
    assert set(SUMMARY) - {"patches"} <= set(summary)
    assert _undocumented(summary) == set()


def test_line_contact_and_wheel_rail_results_carry_documented_fields_only():
    line = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 0.0}, "load": {"normal_force": 100.0},
                            "grid": {"n": 20}, "model": {"theory": "exact"}})
    assert _undocumented(line.summary()) == set() and line.extra["line_contact"] is True
    wr = conformal.solve(DEMO, model__theory="fastsim")
    assert _undocumented(wr.summary()) == set()
    assert wr.extra["FZ_track"] == pytest.approx(10000.0, rel=1e-4)      # the demo's wheel load, balanced


def test_every_field_has_a_meaning_and_the_markdown_lists_it():
    md = markdown()
    for key, f in {**SUMMARY, **EXTRA}.items():
        assert f.doc and f"| `{key}` |" in md
    assert not set(SUMMARY) & set(EXTRA)
