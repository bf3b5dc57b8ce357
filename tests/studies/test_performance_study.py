"""studies/performance.py --quick: the one-table speed study of issue 13 runs end to end and the
numbers it reports are the right ones (forces against their references, the fitted exponent)."""
from __future__ import annotations

import json

import numpy as np
import pytest
from _studies import load_study

CONTACT_FX_100 = -13990.0     # CONTACT GDsteady, case circ at n = 100 (studies/steady_rolling_speed.py)
HERTZ_FN = 32847.0            # meshes/scenes/hertz_crowned_wheel.toml: Hertz at the prescribed approach


def _study():
    return load_study("performance")


def test_growth_exponent_is_the_slope_of_the_logs():
    mod = _study()
    sizes = [50, 100, 200]
    assert mod.growth(sizes, [3.0 * (n * n) ** 1.25 for n in sizes]) == pytest.approx(1.25, abs=1e-12)
    assert mod.growth([100], [1.0]) is None


@pytest.mark.slow
def test_performance_study_quick(tmp_path):
    mod = _study()
    assert mod.main(["--quick", "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "performance.json").read_text())
    text = (tmp_path / "performance.md").read_text()
    assert (tmp_path / "run.json").is_file()
    rows = {r["n"]: r for r in res["halfspace"]}
    assert sorted(rows) == [25, 50, 100]
    # steady rolling: every solve converged and n = 100 gives CONTACT's force within 1 %
    assert all(r["converged"] for r in rows.values())
    assert rows[100]["FX"] == pytest.approx(CONTACT_FX_100, rel=0.01)
    assert all(r["products"] > 0 and r["steady_fft_pairs"] > 0 for r in rows.values())
    # the exponent in the table is the polyfit of the costs over n >= 50
    big = [n for n in rows if n >= 50]
    q = np.polyfit(np.log(np.array(big, float) ** 2), np.log([rows[n]["cost_products"] for n in big]), 1)[0]
    assert res["growth"]["products"] == pytest.approx(q, rel=1e-12)
    # FE pair: both bodies computed (the second in its own process) with their stages
    pair = res["fe_pair"][0]
    assert "error" not in pair and pair["workers"] == 2
    assert pair["rail"]["dofs"] > 1000 and pair["wheel"]["dofs"] > 1000
    # FE scene: the crowned wheel on the flat rail gives Hertz within 0.2 % (docs/validation/models.md: 0.06 %)
    scene = res["fe_scenes"][0]
    assert scene["scene"] == "hertz_crowned_wheel.toml" and "error" not in scene
    assert scene["FN"] == pytest.approx(HERTZ_FN, rel=2e-3)
    # bounded memory: 2.1 GiB measured with the converged default body (fe_body_size 16) on the loaded 2-core machine
    assert scene["peak_gib_self"] < 3.0
    # the demo ran and succeeded
    assert res["demo"]["rc"] == 0 and res["demo"]["wall_s"] > 0
    assert "## Steady rolling" in text and "## `conformal demo`" in text
    # against CONTACT (issue 23): the Manchester cases within 1 % of CONTACT's FN, the import light,
    # and every ratio is our time over CONTACT's stored one
    mb = res["mbench"][0]
    assert "error" not in mb and mb["cases"] == 3 and mb["max_FN_error"] < 0.01
    assert res["startup"]["importtime_s"] < 0.15
    # CONTACT's shift performance case: the same contact and slip elements as CONTACT
    pc = res["perfc_shift"]
    assert (pc["n_contact"], pc["n_slip"]) == (3148, 1730) and pc["converged"]
    for r in res["contact_ratios"]:
        assert r["ratio"] == pytest.approx(r["ours_s"] / r["contact_s"], rel=1e-12) and r["source"]
    assert "## Against CONTACT (issue 23)" in text
