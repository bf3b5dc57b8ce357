"""Every study in studies/ runs end to end in its ``--quick`` mode, writes its outputs and the
sidecar run.json (studies/_provenance.py: commit, arguments, package versions) into the folder
given by ``--out``, and one real number of each output is checked against an independent value:
Hertz's closed form, Kalker's published creep coefficients, CONTACT's printed results, the
prescribed wheel load or a symmetry.

Studies with their own quick tests elsewhere are not repeated here: creep_table_*,
fe_contact_reference, performance, c33_convergence, steady_rolling_speed, and fe_body_size
(tests/validation/test_fe_large_bodies.py::test_body_size_study_quick runs its --quick, 70 s of FE; it writes
the same sidecar through studies/_provenance.py).  Each run is a subprocess (imports included: 2-4 s
on an idle machine); those over about 5 s on the shared machine are marked slow.
"""
from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from _paths import ROOT, STUDIES
from _studies import check_sidecar, run_study


def rows(path: Path) -> list[dict]:
    with path.open(newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_sidecar_records_arguments_and_rejects_a_standard_key_in_extra(tmp_path):
    sys.path.insert(0, str(STUDIES))
    try:
        from _provenance import write_sidecar
    finally:
        sys.path.remove(str(STUDIES))
    args = {"x": 1, "out": str(ROOT / "studies" / "out" / "x"), "elsewhere": str(tmp_path)}
    path = write_sidecar(tmp_path, STUDIES / "profile_sweep.py", args, extra={"summary": {"a": 2}})
    side = json.loads(path.read_text())
    assert side["script"] == "studies/profile_sweep.py" and side["summary"] == {"a": 2}
    assert side["args"] == {"x": 1, "out": "studies/out/x", "elsewhere": str(tmp_path)}   # in-tree paths relative
    with pytest.raises(ValueError, match="standard key"):
        write_sidecar(tmp_path, STUDIES / "profile_sweep.py", {}, extra={"commit": "x"})


def test_quick_without_out_leaves_the_committed_outputs_alone(tmp_path):
    """--quick without --out writes to <tmp>/conformal_studies_quick/<name>, never into
    studies/out/<name> (the committed full outputs)."""
    committed = ROOT / "studies" / "out" / "creep_coefficients" / "creep_coefficients.csv"
    before = committed.stat().st_mtime_ns if committed.exists() else None
    e = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg", TMPDIR=str(tmp_path))
    r = subprocess.run([sys.executable, str(STUDIES / "creep_coefficients.py"), "--quick"], cwd=ROOT,
                       capture_output=True, text=True, timeout=300, env=e)
    assert r.returncode == 0, r.stderr[-2000:]
    out = tmp_path / "conformal_studies_quick" / "creep_coefficients"
    assert (out / "creep_coefficients.csv").exists()
    assert check_sidecar(out, "creep_coefficients")["args"]["out"] == str(out)
    assert (committed.stat().st_mtime_ns if committed.exists() else None) == before


@pytest.mark.slow
def test_halfspace_scaling_quick(tmp_path):
    """CONTACT's case "circ" (G = 82 000, nu = 0.28, A = B = 0.001/mm, FN = 100 kN): at n = 50
    pmax and approach agree with Hertz for a sphere of R = 1/(2A) = 500 mm on identical steel,
    E* = G/(1 - nu), a = (3 FN R / 4 E*)^(1/3), pmax = 3 FN/(2 pi a^2), approach = a^2/R
    (measured: -0.04 %, -0.009 %); steady rolling FX against CONTACT's -14110 N (measured -14114)."""
    out = run_study("halfspace_scaling", tmp_path / "out")
    r = {int(float(x["n"])): x for x in rows(out / "halfspace_scaling.csv")}
    assert sorted(r) == [25, 32, 50]
    G, nu, FN, R = 82000.0, 0.28, 1.0e5, 500.0
    a = (3 * FN * R / (4 * G / (1 - nu))) ** (1 / 3)
    assert float(r[50]["pmax"]) == pytest.approx(3 * FN / (2 * math.pi * a * a), rel=2e-3)
    assert float(r[50]["approach"]) == pytest.approx(a * a / R, rel=5e-4)
    assert float(r[50]["FX"]) == pytest.approx(-14110.0, rel=3e-3)
    assert (out / "halfspace_scaling.png").exists()


@pytest.mark.slow
def test_manchester_a22_quick(tmp_path):
    """Right wheel at 0 and 3 mm (0.4 mm elements): CONTACT's FN 9997 / 9774 N and contact
    positions on the rail -8.66 / -20.563 mm (reference A5, as printed) within 1 % and 0.03 mm."""
    out = run_study("manchester_a22", tmp_path / "out")
    r = {float(x["y_ws"]): x for x in rows(out / "manchester_a22.csv")}
    assert sorted(r) == [0.0, 3.0]
    for y, (FN, y_rail) in {0.0: (9997.0, -8.66), 3.0: (9774.0, -20.563)}.items():
        assert float(r[y]["FN"]) == pytest.approx(FN, rel=0.01)
        assert float(r[y]["y_rail"]) == pytest.approx(y_rail, abs=0.03)
        assert float(r[y]["geo_y_rail"]) == pytest.approx(y_rail, abs=0.03)


@pytest.mark.slow
def test_creep_coefficients_quick(tmp_path):
    """g = 1, nu = 0.25, extrapolated from n = 16, 24, 32: Kalker's C11 = 4.12, C22 = 3.67,
    C23 = 1.47 (Kalker 1990, Table E.3; measured -0.6 %, -0.06 %, +0.6 %).  conformal/data is not
    written in quick mode."""
    data = ROOT / "conformal" / "data" / "kalker_c33.csv"
    before = data.stat().st_mtime_ns if data.exists() else None
    out = run_study("creep_coefficients", tmp_path / "out")
    r = next(x for x in rows(out / "creep_coefficients.csv") if float(x["g"]) == 1.0 and float(x["nu"]) == 0.25)
    assert float(r["C11_inf"]) == pytest.approx(4.12, rel=0.015)
    assert float(r["C22_inf"]) == pytest.approx(3.67, rel=0.015)
    assert float(r["C23_inf"]) == pytest.approx(1.47, rel=0.02)
    assert len(rows(out / "creep_coefficients_convergence.csv")) == 9
    assert (data.stat().st_mtime_ns if data.exists() else None) == before


@pytest.mark.slow
def test_fast_theories_benchmark_quick(tmp_path):
    """FASTSIM with CONTACT's variant (parabolic bound, 44 x 44 grid, CONTACT's discretisation and
    flexibilities) against CONTACT's own FASTSIM: FY/(mu FN) = -0.6118 (as printed)."""
    out = run_study("fast_theories_benchmark", tmp_path / "out")
    r = next(x for x in rows(out / "fast_theories.csv") if x["case"] == "fastsim#2 CONTACT-FASTSIM"
             and x["quantity"] == "FY/(mu FN)" and "contact, CONTACT's L" in x["variant"])
    assert float(r["reference"]) == -0.6118
    assert float(r["value"]) == pytest.approx(-0.6118, abs=2e-4)
    conv = rows(out / "fastsim_convergence.csv")
    assert {int(x["n"]) for x in conv if x["discretisation"] == "contact"} == {44, 220}
    side = json.loads((out / "run.json").read_text())
    assert all(t["wall"] > 0 for t in side["throughput_per_s"])


@pytest.mark.slow
def test_profile_sweep_quick(tmp_path):
    """S1002/UIC60 1:40 from -4 to 4 mm: the symmetric wheelset gives r_R - r_L = 0 at y = 0 and an
    odd function of y (mirror symmetry), and at y = 0 both wheels roll within 0.2 mm of the
    nominal radius 460 mm."""
    out = run_study("profile_sweep", tmp_path / "out")
    r = {float(x["shift"]): x for x in rows(out / "S1002_UIC60_1in40.csv")}
    assert sorted(r) == [float(y) for y in range(-4, 5)]
    assert float(r[0.0]["delta_r"]) == pytest.approx(0.0, abs=1e-9)
    for y in (1.0, 2.0, 3.0, 4.0):
        assert float(r[y]["delta_r"]) == pytest.approx(-float(r[-y]["delta_r"]), abs=1e-6)
        assert float(r[y]["delta_r"]) > 0
    assert float(r[0.0]["r_right"]) == pytest.approx(460.0, abs=0.2)
    assert (out / "overview.png").exists()


@pytest.mark.slow
def test_flange_contact_quick(tmp_path):
    """Flange root at 6.2 mm, four models without FE: every model carries the prescribed 10 kN
    wheel load (track-vertical FZ within 0.1 %), and Hertz+FASTSIM's pmax is the parabolic bound's
    peak 2 FN/(pi a b) (within 1 %: element-centre value)."""
    out = run_study("flange_contact", tmp_path / "out")
    r = rows(out / "flange_contact.csv")
    assert [x["model"] for x in r] == ["Hertz+FASTSIM", "exact, tangent plane", "conformal HS, ref. creepages",
                                       "conformal, half-space"]
    for x in r:
        assert float(x["FZ_track"]) == pytest.approx(10000.0, rel=1e-3), x["model"]
    h = r[0]
    peak = 2 * float(h["FN"]) / (math.pi * float(h["a"]) * float(h["b"]))
    assert float(h["pmax"]) == pytest.approx(peak, rel=0.01)


@pytest.mark.slow
def test_seed_wheelset_quick(tmp_path):
    """Coarse table, 0.1 s of FASTSIM at 65 m/s: the right wheel carries the static wheel load of
    Table 1 (49 kN) within 2 %, and the linear critical speed is within 5 % of the seed's 69 m/s
    (Valtorta et al. 2001; measured 71.3)."""
    out = run_study("seed_wheelset", tmp_path / "out")
    res = json.loads((out / "seed_wheelset.json").read_text())
    assert res["response"]["fastsim"]["max_right_FZ"] == pytest.approx(49000.0, rel=0.02)
    assert res["linear_critical_speed"] == pytest.approx(69.0, rel=0.05)


@pytest.mark.slow
def test_speed_vs_error_quick(tmp_path):
    """Flange root at 6.2 mm, grids n = 12, 16 against conformal HS n = 24 (no FE in quick mode):
    every model carries the prescribed 10 kN wheel load (track-vertical FZ within 0.1 %), the
    reference row has zero error and the conformal half-space grids converge towards it
    (measured force error 0.25 % at n = 12, 0.11 % at n = 16)."""
    out = run_study("speed_vs_error", tmp_path / "out")
    r = {x["model"]: x for x in rows(out / "speed_vs_error.csv")}
    assert {x.split(" n=")[0] for x in r} == {"hertz", "linear", "empirical", "fastsim", "exact", "conformal HS"}
    for x in r.values():
        assert float(x["FZ_track"]) == pytest.approx(10000.0, rel=1e-3), x["model"]
    assert float(r["conformal HS n=24 (reference)"]["force_error"]) == 0.0
    e12, e16 = (float(r[f"conformal HS n={n}"]["force_error"]) for n in (12, 16))
    assert e16 < e12 < 0.01


@pytest.mark.slow
def test_fe_influence_speed_error_quick(tmp_path):
    """The FE speed/error study: with the half-space far field the split method is exact on the flat
    block (e_off ~ 1e-8 of the self term, roundoff), a clamped block carries the truncation offset
    (-0.56 % of the self term measured, a few 0.1 %), and its kernels land in --out, not in
    studies/out."""
    out = run_study("fe_influence_speed_error", tmp_path / "fise", timeout=900.0)
    d = json.loads((out / "fe_influence_speed_error.json").read_text())
    flat = {r["name"]: r for r in d["flat"]}
    assert flat["split P1 default (half-space far field)"]["e_off"] < 1e-6
    clamped = flat["split P1 h=d, clamped"]
    assert -0.01 < clamped["offset_zz"] < -0.002 and clamped["e_off"] < 0.005
    assert sorted(p.name for p in out.glob("fe_kernel_*.npy")) == ["fe_kernel_gauge_P1_2_0.5.npy",
                                                                    "fe_kernel_gauge_P2_0.5_None.npy"]
    assert "| gauge split P1 h=2d col 0.5d |" in (out / "fe_influence_speed_error.md").read_text()


@pytest.mark.slow
def test_speed_vs_error_rerun_one_cell(tmp_path):
    """``--only SHIFT MODEL`` reruns one cell against the stored reference row and merges it: on a
    copy of the stored outputs, the half-space n = 16 cell of the flange root (6.2 mm) computed
    again reproduces its stored force and pmax errors (0.09 % / 0.1 %: the same model on the same
    scene, against the same stored FE reference) and leaves every other row as it was; an unknown
    model is refused with exit code 2."""
    import shutil

    out = tmp_path / "out"
    shutil.copytree(STUDIES / "out" / "speed_vs_error", out)
    before = rows(out / "speed_vs_error.csv")
    e = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    cmd = [sys.executable, str(STUDIES / "speed_vs_error.py"), "--out", str(out), "--only", "6.2"]
    r = subprocess.run(cmd + ["conformal HS n=16"], cwd=ROOT, capture_output=True, text=True, timeout=300, env=e)
    assert r.returncode == 0, r.stderr[-2000:]
    after = rows(out / "speed_vs_error.csv")
    assert len(after) == len(before)
    key = ("flange root, y = 6.2", "conformal HS n=16")
    for a, b in zip(before, after):
        if (a["scene"], a["model"]) == key:
            assert float(b["force_error"]) == pytest.approx(float(a["force_error"]), rel=1e-3, abs=1e-6)
            assert float(b["pmax_error"]) == pytest.approx(float(a["pmax_error"]), rel=1e-3, abs=1e-6)
        else:
            assert a == b
    side = json.loads((out / "run.json").read_text())
    assert side["rerun_cell"] == list(key) and side["earlier_runs"][0]["args"]["quick"] is False
    bad = subprocess.run(cmd + ["no such model"], cwd=ROOT, capture_output=True, text=True, timeout=300, env=e)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
