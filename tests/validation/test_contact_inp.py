"""``conformal inp``: CONTACT's public input decks against their reference outputs.

The decks and their reference totals are in tests/reference/contact_decks (CONTACT, Apache-2.0;
README there).  Every case the reader supports is solved and compared with CONTACT's printed
totals: FN, FX, FY, MZ, pmax, approach and the solved creepage or shift within one unit of the
last printed digit (4 significant digits), the numbers of elements in contact, adhesion and slip
exactly.  manifest.json counts the supported cases of every public deck; the test checks that the
reader still supports exactly those.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from conformal.cli import main
from conformal.contact_inp.combine import PREFIX
from conformal.contact_inp.deck import plan, read_deck, solve_deck
from conformal.contact_inp.module3 import Unsupported
from conformal.contact_inp.refout import compare, read_ref_out
from conformal.errors import InputError
from _paths import DECKS

MANIFEST = json.loads((DECKS / "manifest.json").read_text(encoding="utf-8"))
SUPPORTED = {Path(e["deck"]).name: e for e in MANIFEST["decks"] if e["supported"]}
#: decks compared to CONTACT's printed digits (module 3); module 1 runs the project's own wheel-rail
#: geometry processing and is compared within the Manchester tolerances instead
DIGITS = {name: e for name, e in SUPPORTED.items() if 3 in e.get("module", [])}
WHEELRAIL = {name: e for name, e in SUPPORTED.items() if 1 in e.get("module", [])}
#: a subset of the long decks (slow-lane budget, < 90 s): the first cases of each sequence (a
#: sequence always starts at its first case) and every third independent case; the numbers in docs/how-to/contact-decks.md
#: come from all cases (tests/reference/contact_decks/extract.py and conformal inp)
SUBSET = {"spence35.inp": lambda n: n <= 15, "catt_to_cart.inp": lambda n: n <= 20 or 60 <= n <= 80,
          "tractcurv.inp": lambda n: n % 3 == 1, "tractcurve_plast.inp": lambda n: n % 3 == 1,
          "euro_tractcurv.inp": lambda n: n % 3 == 1}

#: decks that take longer than a few seconds (slow lane)
SLOW = {"spence35.inp", "catt_to_cart.inp", "tractcurv.inp", "tractcurve_plast.inp", "bentall.inp", "euro_tractcurv.inp",
        "testbank.inp"}

#: cases where the project differs from CONTACT: (what differs, the warning the case carries or
#: None); the test checks that each one still differs (a fix shows up as a failure: remove it)
KNOWN: dict = {
    # (testbank case 17, one transient step of dq = 2 dx from zero tractions, xi -0.04434 against
    # -0.04500, agrees since the leading-edge correction of conformal.solvers.history)
}


def _params():
    for name in sorted(DIGITS):
        marks = [pytest.mark.slow] if name in SLOW else []
        yield pytest.param(name, marks=marks, id=name)


@pytest.mark.parametrize("name", list(_params()))
def test_public_deck_against_contact(name):
    entry = SUPPORTED[name]
    parsed = read_deck(DECKS / name, ignore_subsurface=True, ignore_temperature=True)
    pl = plan(parsed)
    # cases with friction over the profile (V = 1) that the solve found not constant over a patch
    assert sum(len(chain) for chain in pl.chains) == entry["supported"] + len(entry.get("refused_after_solve", []))
    ok = [c.number for chain in pl.chains for c, _ in chain if getattr(c, "module", 3) == 3]
    ok = [n for n in ok if SUBSET.get(name, lambda n: True)(n)]
    ref = read_ref_out((DECKS / name).with_suffix(".ref_out").read_text(encoding="utf-8"))
    solved = compared = 0
    for d in solve_deck(parsed, cases=ok):
        solved += 1
        if d["case"] not in ref:           # CONTACT printed no totals (output digit O = 1)
            continue
        compared += 1
        bad = compare(d, ref[d["case"]])
        known = KNOWN.get((name, d["case"]))
        if known is None:
            assert not bad, f"{name} case {d['case']}: (ours, CONTACT) {bad}"
        else:
            key, warning = known
            assert key in bad, f"{name} case {d['case']}: now agrees? {bad}"
            assert warning is None or any(warning in w for w in d["warnings"])
    assert solved == len(ok) and compared >= solved - 1


def test_supported_fraction_in_the_manifest():
    """The manifest's totals are the sums of its decks; every supported deck is here."""
    decks = MANIFEST["decks"]
    assert MANIFEST["cases"] == sum(e["cases"] for e in decks)
    assert MANIFEST["supported"] == sum(e["supported"] for e in decks)
    for e in decks:
        assert e["supported"] <= e["cases"]
        if e["supported"] < e["cases"]:
            assert e["reasons"], e["deck"]           # every unsupported case has a reason
    assert {p.name for p in DECKS.glob("*.inp")} == set(SUPPORTED)
    assert set(DIGITS) | set(WHEELRAIL) == set(SUPPORTED)
    assert sum(SUPPORTED[n]["supported"] for n in ("mbench_a22_left.inp", "mbench_a22_right.inp")) == 42
    # module-1 cases run with the patch-combination warning: supported, not counted as agreeing
    assert MANIFEST["patch_combination"] == sum(len(e.get("patch_combination", [])) for e in decks)
    for e in decks:
        assert len(set(e.get("patch_combination", []))) == len(e.get("patch_combination", []))
        assert not set(e.get("patch_combination", [])) & set(e.get("refused_after_solve", []))
        assert len(e.get("patch_combination", [])) <= e["supported"]


@pytest.mark.slow
def test_patch_combination_cases_of_the_manifest():
    """The manifest's ``patch_combination`` cases of the site-B and testbank decks are those where
    CONTACT's rule differs at the normal balance (tests/reference/contact_decks/extract.py)."""
    from conformal.contact_inp.combine import loaded_warnings
    from conformal.contact_inp.solve1 import thresholds
    from conformal.errors import ConvergenceError, NoContactError
    from conformal.scene import scene_from_dict

    for name in ("iestim_site_b.inp", "testbank.inp"):
        pl = plan(read_deck(DECKS / name, ignore_subsurface=True, ignore_temperature=True))
        found = []
        for case, raw in (item for chain in pl.chains for item in chain):
            if getattr(case, "module", 3) != 1:
                continue
            try:
                if loaded_warnings(scene_from_dict(raw, base_dir=DECKS, name=raw["name"]), *thresholds(case)):
                    found.append(case.number)
            except (InputError, NoContactError, ConvergenceError):
                pass
        assert found == WHEELRAIL[name].get("patch_combination", []), name


def test_contacts_rule_for_contact_regions():
    """CONTACT's distance between interpenetration regions (gaps of the x and y extents, height
    difference at the facing lateral ends) and its four treatments by D_COMB <= D_SEP <= D_TURN."""
    from conformal.contact_inp.combine import Region, contact_treatment, region_distance

    a = Region(x=(-5.0, 5.0), y=(0.0, 10.0), z=(0.0, 1.0), angle=0.0, s=(0.0, 10.0))
    b = Region(x=(-3.0, 3.0), y=(13.0, 20.0), z=(5.0, 6.0), angle=0.5, s=(15.0, 22.0))
    c = Region(x=(8.0, 9.0), y=(2.0, 4.0), z=(0.0, 0.0), angle=0.0, s=(2.0, 4.0))
    assert region_distance(a, b) == pytest.approx(5.0) == region_distance(b, a)   # dy 3, dz 4
    assert region_distance(a, c) == pytest.approx(3.0)                            # x only
    assert region_distance(a, a) == 0.0
    th = dict(d_comb=4.0, d_sep=8.0, d_turn=12.0, a_sep=1.0)
    assert [contact_treatment(d, 0.1, **th) for d in (4.0, 4.1, 8.0, 12.0, 12.1)] == [
        "combined", "blended", "blended", "turned", "separate"]
    assert contact_treatment(1.0, 1.2, **th) == "separate"                         # angles too far apart


def test_patch_combination_warning_names_d_comb():
    """Testbank case 35 (conformal, Z_WS prescribed): CONTACT combines its three interpenetration
    regions (8.9 and 14.9 mm apart, D_COMB = 20 mm) into one patch; this reader solves separate
    strips and says so.  mbench_conf case 1 (two patches 20 mm apart, D_SEP 9 mm, D_TURN 12 mm
    by default): no warning.  The CLI repeats each such warning on stderr."""
    from conformal.contact_inp.combine import loaded_warnings
    from conformal.contact_inp.deck import deck_scene
    from conformal.contact_inp.solve1 import thresholds
    from conformal.scene import scene_from_dict

    for name, number, expect in (("testbank.inp", 35, 2), ("mbench_conf.inp", 1, 0)):
        case = read_deck(DECKS / name).cases[number - 1]
        assert case.number == number
        sc = scene_from_dict(deck_scene(DECKS / name, number), base_dir=DECKS)
        w = loaded_warnings(sc, *thresholds(case))
        assert len(w) == expect, w
        assert all("D_COMB = 20 mm" in t and "separate patches" in t for t in w)
        assert (number in WHEELRAIL[name].get("patch_combination", [])) == bool(expect)


def test_cli_prints_the_patch_combination_warning(tmp_path, capsys, monkeypatch):
    """One stderr line per such warning, naming the case; other warnings stay in the JSON only."""
    import conformal.contact_inp.deck as deck

    text = f"{PREFIX} CONTACT combines contact regions closer than D_COMB = 3 mm (regions 1.20 mm apart)"
    monkeypatch.setattr(deck, "read_deck", lambda *a, **k: None)
    monkeypatch.setattr(deck, "solve_deck", lambda *a, **k: iter([{"case": 4, "warnings": [text, "other"]}]))
    assert main(["inp", str(tmp_path / "x.inp")]) == 0
    out = capsys.readouterr()
    assert json.loads(out.out)["warnings"] == [text, "other"]
    assert out.err.strip().splitlines() == [f"case 4: {text}"]


def test_wheelrail_decks_map_onto_scenes():
    """Every case of the module-1 decks becomes a valid wheel-rail scene (profiles beside the deck,
    track, wheelset position and velocity), without solving."""
    from conformal.scene import scene_from_dict

    for name in WHEELRAIL:
        pl = plan(read_deck(DECKS / name, ignore_subsurface=True, ignore_temperature=True))
        items = [item for chain in pl.chains for item in chain if getattr(item[0], "module", 3) == 1]
        for case, scene in items:
            sc = scene_from_dict(scene, base_dir=DECKS)
            assert sc.geometry.side == case.side
            if case.digits["N"] == 1:                      # the vertical force; N = 0: the height Z_WS
                assert sc.load.wheel_load == case.position[2]
            else:
                assert sc.load.approach > 0
            assert sc.geometry.lateral_shift == case.position[1]
            if case.friction_table and not case.conformal:  # V = 1, planar: one friction per patch
                assert sc.friction.angle_table == case.friction_table


@pytest.mark.slow
@pytest.mark.parametrize("name, cases", [("mbench_a22_right.inp", [1, 13])])
def test_wheelrail_deck_against_contact(name, cases):
    """Manchester A-2.2 (right wheel, y_ws = 0 and 6 mm) through ``conformal inp``: patch forces and
    track forces within max(1 %, 0.002 mu FN), contact angle 0.005 rad, position on the rail
    0.2 mm, pmax 3 %, contact elements 10 % (the project's own profile processing: docs/how-to/contact-decks.md)."""
    from conformal.contact_inp.refout import compare_wheelrail, read_ref_out_wheelrail

    parsed = read_deck(DECKS / name)
    ref = read_ref_out_wheelrail((DECKS / name).with_suffix(".ref_out").read_text(encoding="utf-8"))
    rows = list(solve_deck(parsed, cases=cases))
    assert [d["case"] for d in rows] == cases
    for d in rows:
        dev = compare_wheelrail(d, ref[d["case"]], mu=0.3)
        assert dev and max(dev.values()) <= 1.0, (d["case"], {k: v for k, v in dev.items() if v > 1})
        assert {"FX_track", "FY_track", "FZ_track", "patches"} <= set(d)
        assert d["case"] not in WHEELRAIL[name].get("patch_combination", [])
        assert not [w for w in d["warnings"] if w.startswith(PREFIX)]


#: conformal (D = 4) module-1 cases against CONTACT (its .ref_out), with tolerances (%; angle in
#: degrees) set from the agreement measured with the same formulation built by hand
#: (tests/validation/test_contact_conformal.py, docs/validation/flange-contact.md "CONTACT's conformal formulation"): groove_li pitch
#: creepage +0.15 .. +0.17 %, pmax 0.04 %, area 0.22 %, TILDE_FN 0.07 %; mbench_conf FN -1.1 / +0.1 %,
#: FX -1.3 / 0.0 %, FS -1.1 / -0.5 %, pmax -0.3 / -0.2 %, 320 / 128 elements for 321 / 129, track
#: forces -0.9, -0.4, -1.0 %.  The issue's targets: the groove's pitch within 1 %, the flange FN within 2 %.
CONFORMAL_TOL = {
    "groove_li.inp": {"pitch_creepage": 1.0, "FN": 0.5, "pmax": 0.5, "n_contact": 1.0, "FZ_track": 0.01,
                      "FX_track": 0.01, "FY_track": 0.01, "bar_FN": 0.5, "angle": 0.5, "FX": 0.1, "bar_FS": 0.1},
    "mbench_conf.inp": {"FN": 2.0, "bar_FN": 2.0, "FX": 2.0, "bar_FS": 2.0, "pmax": 1.0, "n_contact": 1.0,
                        "angle": 1.0, "FX_track": 2.0, "FY_track": 2.0, "FZ_track": 2.0},
}


@pytest.mark.slow
@pytest.mark.parametrize("name, case", [("groove_li.inp", 1), ("mbench_conf.inp", 1)])
def test_conformal_deck_against_contact(name, case):
    """CONTACT's conformal decks (module 1, D = 4) through ``conformal inp``: groove_li (free
    rolling, FX_WS = 0 prescribed with F = 1, the pitch solved; R 10.25 mm, about 30 s; case 4,
    R 10.02 mm, passes too but takes 2 minutes: docs/how-to/contact-decks.md) and mbench_conf (Z_WS prescribed with N = 0,
    friction over the profile V = 1, two patches; about 6 s)."""
    from conformal.contact_inp.refout import compare_conformal, read_ref_out_wheelrail

    parsed = read_deck(DECKS / name)
    ref = read_ref_out_wheelrail((DECKS / name).with_suffix(".ref_out").read_text(encoding="utf-8"))
    (d,) = list(solve_deck(parsed, cases=[case]))
    dev = compare_conformal(d, ref[case], nomrad=parsed.cases[case - 1].wheelset[2])
    tol = CONFORMAL_TOL[name]
    bad = {k: round(v, 3) for k, v in dev.items() if abs(v) > tol[k.split(".")[-1]]}
    assert not bad, (name, case, bad)
    # CONTACT's rule for contact regions agrees with the patches solved here (two patches far apart)
    assert not [w for w in d["warnings"] if w.startswith(PREFIX)]
    if name == "groove_li.inp":
        assert "pitch_creepage" in dev and len(d["patches"]) == 1
    else:
        assert len(d["patches"]) == 2 and abs(dev["patch2.FN"]) < 2.0       # the flange patch (issue 21)
        # each strip's reference point on the rail (CONTACT's YCP(R)): -35.128 / -42.233 against
        # -35.163 / -42.229 mm (it was null for conformal strips)
        ours = sorted((p["FN"], p["y_rail"]) for p in d["patches"])
        theirs = sorted((float(p["TILDE_FN"]), float(p["YCP(R)"])) for p in ref[case]["patches"])
        assert [y for _, y in ours] == pytest.approx([y for _, y in theirs], abs=0.05)


@pytest.mark.slow
def test_height_and_friction_per_patch_against_contact():
    """Planar module-1 cases with the wheelset height prescribed (N = 0: ``[load] approach`` from
    the first touch) and friction over the surface inclination (V = 1: ``[friction] angle_table``,
    one coefficient per patch at its contact angle, as CONTACT): ``iestim_site_b`` cases 2 and 4
    (worn wheel on a measured rail, mu 0.2 below -30 degrees, 0.35 above -20; case 4 with a tread
    and a flange patch) within the Manchester tolerances of CONTACT (the metric of
    :func:`test_wheelrail_deck_against_contact`); ``mbench_a22_varfric`` case 3 (two patches, mu
    0.2 below -20 degrees, 0.3 above -10): the tread patch slides fully, its force is mu FN with
    the table's value at its own contact angle, not the flange patch's (about 15 s)."""
    from conformal.contact_inp.refout import compare_wheelrail, read_ref_out_wheelrail
    from conformal.specs import Friction

    name = "iestim_site_b.inp"
    ref = read_ref_out_wheelrail((DECKS / name).with_suffix(".ref_out").read_text(encoding="utf-8"))
    rows = list(solve_deck(read_deck(DECKS / name), cases=[2, 4]))
    assert [len(d["patches"]) for d in rows] == [1, 2]
    for d in rows:
        dev = compare_wheelrail(d, ref[d["case"]], mu=0.2)
        assert max(dev.values()) <= 1.0, (d["case"], {k: v for k, v in dev.items() if v > 1})
        assert d["z_ws"] == pytest.approx(1.13 + 0.01 * (d["case"] - 1), abs=1e-9)   # Z_WS of the deck
    parsed = read_deck(DECKS / "mbench_a22_varfric.inp", ignore_subsurface=True)
    (d,) = list(solve_deck(parsed, cases=[3]))
    table = Friction(0.3, 0.3, angle_table=parsed.cases[2].friction_table)
    mus = [table.at_angle(p["contact_angle"]).mu_static for p in d["patches"]]
    ratios = [np.hypot(p["FX"], p["FS"]) / p["FN"] for p in d["patches"]]
    assert sorted(mus)[0] < 0.25 and sorted(mus)[1] == 0.3
    tread = int(np.argmax(mus))
    assert ratios[tread] == pytest.approx(0.3, rel=1e-3)
    assert all(r <= m * (1 + 1e-6) for r, m in zip(ratios, mus))


def test_friction_per_grid_row_in_full_slip(tmp_path):
    """Module 3 with V = 3 (FSTAT, FKIN per grid row, read after the geometry): in full slip
    (CKSI = 0.1) every element carries mu of its row times its pressure, so FX = -sum mu_j p_ij
    dx dy and the rows with less friction carry less (the per-element bound of the exact solver,
    conformal.solvers.exact); FKIN / FSTAT varying between the rows is refused by name."""
    mus = [0.1 + 0.02 * j for j in range(10)]
    text = ("% V = 3\n 3  MODULE\n  203100\n 3022020\n 0001341\n   100 100 30 1 1e-8\n"
            "   1000.  0.1  0.0  0.0\n   0.0  0.5  30000.\n   0.28 0.28 82000 82000\n    1\n"
            "   10 10 -2.5 -2.5 0.5 0.5\n    1 1\n   0.002 0 0.002 0 0 0\n"
            + "".join(f"   {m:.2f} {m:.2f}\n" for m in mus) + " 0\n")
    (tmp_path / "rows.inp").write_text(text)
    from conformal.contact_inp.solve3 import summary
    from conformal.models import solve_problem

    ((case, p),), = plan(read_deck(tmp_path / "rows.inp")).chains
    assert p.mu_scale[:, 0] == pytest.approx(1.0) and p.mu_scale[3, 9] == pytest.approx(mus[9] / mus[0])
    r = solve_problem(p)
    d = summary(case, r)
    assert d["n_slip"] == d["n_contact"] > 0
    mu = np.broadcast_to(np.array(mus), r.field.pn.shape)
    assert d["FX"] == pytest.approx(-float((mu * r.field.pn).sum()) * 0.25, rel=1e-6)
    assert d["FN"] == pytest.approx(1000.0) and -d["FX"] / d["FN"] < max(mus)
    (tmp_path / "ratio.inp").write_text(text.replace(f"   {mus[4]:.2f} {mus[4]:.2f}\n", f"   {mus[4]:.2f} 0.1\n"))
    with pytest.raises(Unsupported, match="FKIN / FSTAT varying between the grid rows"):
        list(solve_deck(read_deck(tmp_path / "ratio.inp")))


def test_conformal_decks_map_their_digits():
    """groove_li: D = 4 with C = 2 (cases 1-4) and with Blanco's angle correction C = 4 (cases 5-8:
    IF_METH = 1, VARIANT = 3, kept by C = 1 in cases 6-8); F = 1 becomes FX_WS / (mu FZ) with the
    pitch solved; mbench_conf: N = 0 becomes the approach from the first touch, V = 1 the table of
    friction over the surface inclination (``[friction] angle_table``)."""
    from conformal.specs import Friction

    pl = plan(read_deck(DECKS / "groove_li.inp"))
    assert [c.number for chain in pl.chains for c, _ in chain] == [1, 2, 3, 4, 5, 6, 7, 8] and not pl.unsupported
    for chain in pl.chains[4:]:
        assert chain[0][1]["model"] == {"theory": "conformal", "influence": "halfspace_blanco", "blanco_method": "full",
                                        "blanco_variant": 3}
    (c1, s1), = pl.chains[0]
    assert s1["model"] == {"theory": "conformal", "influence": "halfspace_planar"}
    assert s1["kinematics"]["fx_rel"] == 0.0 and s1["geometry"]["placement"] == "single"
    assert (s1["geometry"]["element_size"], s1["geometry"]["element_size_s"]) == (0.095833, 0.25)
    pm = plan(read_deck(DECKS / "mbench_conf.inp"))
    (c, s), = pm.chains[0]
    assert s["load"]["approach"] > 0 and "wheel_load" not in s["load"]
    table = Friction(0.3, 0.3, angle_table=c.friction_table)
    assert s["friction"] == {"angle_table": [list(r) for r in c.friction_table]}
    assert table.at_angle(-0.5).mu_static == 0.2 and table.at_angle(0.0).mu_kinetic == 0.3
    assert table.at_angle(-0.2617994).mu_static == pytest.approx(0.25)


@pytest.mark.slow
def test_friction_per_row_of_a_conformal_strip(tmp_path):
    """mbench_conf with the friction ramp moved to -30 .. -10 degrees, so that the gauge-corner
    patch (around -24 degrees) spans it: every row of the conformal strip gets the friction at its
    own contact angle (``[friction] angle_table``, as CONTACT's V = 1 per grid row).  On the solved
    strip every element obeys Coulomb's law with its row's mu: |p_t| = mu(delta) p_n where it slips,
    <= where it adheres, and both coefficients of the ramp occur (about 10 s)."""
    from conformal.cases.conformal import curved_problem_from_wheel_rail
    from conformal.result import SLIP
    from conformal.scene import scene_from_dict
    from conformal.solvers.conformal import solve_curved
    from conformal.specs import Friction

    text = (DECKS / "mbench_conf.inp").read_text(encoding="latin-1").replace("  -20d    0.200", "  -30d    0.200", 1)
    for name in ("MBench_S1002_v3.prw", "MBench_UIC60_v3.prr"):
        (tmp_path / name).write_bytes((DECKS / name).read_bytes())
    (tmp_path / "ramp.inp").write_text(text, encoding="latin-1")
    ((case, raw),), = plan(read_deck(tmp_path / "ramp.inp")).chains
    table = Friction(0.3, 0.3, angle_table=case.friction_table)
    assert raw["friction"] == {"angle_table": [list(r) for r in case.friction_table]}
    problem = curved_problem_from_wheel_rail(scene_from_dict(raw, base_dir=tmp_path))
    r = solve_curved(problem)
    f = r.field
    mu = np.vectorize(lambda a: table.at_angle(float(a)).mu_static)(f.delta)
    inside = f.pn > 0
    pt = np.hypot(f.px, f.py)
    assert np.all(pt[inside] <= mu[inside] * f.pn[inside] * (1 + 1e-6) + 1e-9)
    slip = f.status == SLIP
    assert slip.sum() > 10
    assert pt[slip] == pytest.approx(mu[slip] * f.pn[slip], rel=1e-5)
    assert mu[inside].min() == pytest.approx(0.2) and 0.2 < mu[inside].max()
    assert len({round(float(m), 6) for m in mu[inside]}) > 3       # the ramp, row by row


def test_conformal_example_reproduces_contacts_digits():
    """examples/conformal cases 1, 2, 4 (45-degree conformal contact, R 10 in R 10.2, the deck gives
    the undeformed distance and case 4 the rigid slip per element): the exact solver with planar
    half-space numbers on the developed grid prints CONTACT's digits (its .ref_out)."""
    parsed = read_deck(DECKS / "conformal.inp")
    got = {d["case"]: d for d in solve_deck(parsed, cases=[1, 2, 4])}
    assert f"{got[2]['FN']:.3e}" == "9.184e+04" and round(got[2]["pmax"]) == 1012 and got[2]["n_contact"] == 871
    assert f"{got[1]['FN']:.3e}" == "1.000e+05" and f"{got[1]['pmax']:.1f}" == "912.8" and got[1]["n_contact"] == 1027
    assert f"{got[4]['FX']:.3e}" == "1.050e+04" and f"{got[4]['FY']:.3e}" == "2.251e+04"
    assert f"{got[4]['MZ']:.3e}" == "3.227e+04" and got[4]["n_slip"] == 871
    with pytest.raises(Unsupported, match="case 3.*inflcf_r10_mx51.txt is missing"):
        list(solve_deck(parsed))


DECK = """% two cases: the second keeps grid, geometry, material and friction (D = C = Z = 0, L = 1)
 3  MODULE
  203100   PBTNFS
  022020   LDCMZE
 0001341   HGIAOWR
   100 100 30 1 1e-8      MAXGS MAXIN MAXNR MAXOUT EPS
   1000.  0.0  -0.002  0.0   FN CKSI CETA CPHI
   0.3 0.3                   FSTAT FKIN
   0.0  0.5  30000.          CHI DQ VELOC
   0.28 0.28 82000 82000     POISS GG
    1                        IPOTCN
   20 20 -5.0 -5.0 0.5 0.5   MX MY XL YL DX DY
    1 1                      IBASE IPLAN
   0.002 0 0.002 0 0 0       B1 .. B6
 3  MODULE
  203100   PBTNFS
  100000   LDCMZE
 0001341   HGIAOWR
   100 100 30 1 1e-8
   1500.  0.0  -0.002  0.0   FN CKSI CETA CPHI
 0  MODULE
"""


def test_later_cases_inherit_earlier_data(tmp_path):
    """Case 2 keeps everything but the load: the same as a deck that repeats all inputs."""
    (tmp_path / "two.inp").write_text(DECK)
    full = DECK.replace("  100000   LDCMZE\n 0001341   HGIAOWR\n   100 100 30 1 1e-8\n   1500.  0.0  -0.002  0.0   FN CKSI CETA CPHI\n",
                        "  022020   LDCMZE\n 0001341   HGIAOWR\n   100 100 30 1 1e-8\n   1500.  0.0  -0.002  0.0\n"
                        "   0.3 0.3\n   0.0  0.5  30000.\n   0.28 0.28 82000 82000\n    1\n"
                        "   20 20 -5.0 -5.0 0.5 0.5\n    1 1\n   0.002 0 0.002 0 0 0\n")
    (tmp_path / "full.inp").write_text(full)
    a = list(solve_deck(read_deck(tmp_path / "two.inp")))
    b = list(solve_deck(read_deck(tmp_path / "full.inp")))
    assert [d["case"] for d in a] == [1, 2]
    assert a[1]["FN"] == pytest.approx(1500.0) and a[1]["FY"] == pytest.approx(b[1]["FY"], rel=1e-12)
    assert a[1]["n_contact"] == b[1]["n_contact"] > a[0]["n_contact"]


def test_cli_writes_json_lines_and_refuses_unsupported_digits(tmp_path, capsys):
    (tmp_path / "two.inp").write_text(DECK)
    assert main(["inp", str(tmp_path / "two.inp"), "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out.splitlines()
    rows = [json.loads(x) for x in out]
    assert [r["case"] for r in rows] == [1, 2]
    for key in ("FN", "FX", "FY", "MZ", "pmax", "approach", "n_contact", "n_adhesion", "n_slip"):
        assert key in rows[0]
    assert (tmp_path / "out" / "two.jsonl").read_text().splitlines() == out
    # velocity-dependent friction: one line naming the digit, exit 2, nothing printed
    (tmp_path / "veldep.inp").write_text(DECK.replace("  022020   LDCMZE", "  422020   LDCMZE", 1)
                                         .replace("   0.3 0.3                   FSTAT FKIN",
                                                  "   0.3 0.1 0.1 0.0 0.0\n   0.0 0.0", 1))
    assert main(["inp", str(tmp_path / "veldep.inp")]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1 and "L = 4 (velocity-dependent friction)" in cap.err
    # a module-1 (wheel-rail) deck with a transient shift (T = 1)
    text = (DECKS / "mbench_a22_right.inp").read_text(encoding="latin-1")
    (tmp_path / "m1.inp").write_text(text.replace(" 1203100 ", " 1201100 ", 1))
    assert main(["inp", str(tmp_path / "m1.inp")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "case 1): not supported: module 1, control digit T = 1" in err
    assert main(["inp", str(tmp_path / "two.inp"), "--cases", "3"]) == 2
    assert "--cases" in capsys.readouterr().err


def test_tokens_of_contacts_free_format():
    from conformal.contact_inp.tokens import Deck, parse_real

    assert parse_real("180d", angle=True) == pytest.approx(np.pi)
    assert parse_real(".1-07") == pytest.approx(1e-8) and parse_real("3.5E-1") == 0.35
    assert parse_real("180d") is None and parse_real("MX,MY") is None
    d = Deck("t.inp", " 1, 2\n 3 % comment\n  4 5 6 trailing words 7\n 'f.prr' rest\n")
    assert d.ints(3, "three") == [1, 2, 3]             # a group over several lines
    assert d.reals(2, "two", optional=1) == [4.0, 5.0, 6.0]   # the optional value on the same line
    assert d.string("name") == "f.prr"
    with pytest.raises(InputError, match="unexpected end of file"):
        d.ints(1, "more")
    with pytest.raises(InputError, match="control word"):
        Deck("t.inp", " 12345678\n").digits("PBTNFS")


def test_one_element_start_of_the_normal_problem_grows_the_contact():
    """A starting pressure on one element (the previous step of a growing load) must not stop the
    contact area from growing (Polonsky-Keer with a uniform gap on the contact set)."""
    from conformal.grid import PlanarGrid
    from conformal.materials import Material
    from conformal.solvers.normal import solve_normal

    g = PlanarGrid.centred(15, 15, 0.2, 0.2)
    X, Y = g.mesh()
    h = 0.004 * (X**2 + Y**2)
    start = np.zeros(g.shape)
    start[7, 7] = 1.0
    mat = Material.identical(1000.0, 0.3)
    fresh = solve_normal(None, g, h, normal_force=0.5, material=mat, tol=1e-9)
    warm = solve_normal(None, g, h, normal_force=0.5, material=mat, tol=1e-9, p_start=start)
    assert fresh.contact.sum() > 1
    assert np.array_equal(warm.contact, fresh.contact)
    assert warm.pmax == pytest.approx(fresh.pmax, rel=1e-6)


def test_history_with_a_moving_undeformed_distance():
    """``solve_history(..., undeformed=...)``: one undeformed distance per applied step; the same h
    for every step gives the plain history, a wrong count is refused."""
    from conformal.problem import problems_from_scene
    from conformal.scene import scene_from_dict
    from conformal.solvers.history import solve_history
    from conformal.specs import HistoryStep

    p = problems_from_scene(scene_from_dict({"geometry": {"kind": "hertz", "a": 1.0, "b": 1.0},
                                             "load": {"normal_force": 1000.0}, "grid": {"n": 16},
                                             "model": {"theory": "exact"}}))[0]
    steps = [HistoryStep(fx_rel=-0.5), HistoryStep(fx_rel=-0.8)]
    plain = solve_history(p, steps)
    same = solve_history(p, steps, undeformed=[p.h, p.h])
    assert [s.FX for s in same.steps] == pytest.approx([s.FX for s in plain.steps], rel=1e-12)
    assert same.shift[-1] == pytest.approx(plain.shift[-1], rel=1e-12)
    with pytest.raises(InputError, match="one undeformed distance"):
        solve_history(p, steps, undeformed=[p.h])


def test_cli_out_must_be_a_folder(tmp_path, capsys):
    (tmp_path / "two.inp").write_text(DECK)
    (tmp_path / "file").write_text("x")
    assert main(["inp", str(tmp_path / "two.inp"), "--out", str(tmp_path / "file")]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["inp", str(tmp_path / "missing.inp")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_leading_edge_factor_of_a_transient_step():
    """CONTACT's leading-edge correction (T = 2 with dq = 2 dx): the last contact element of a run
    along x spent half the step inside the contact, the others all of it; dq = dx changes nothing."""
    from conformal.solvers.history import leading_edge_factor

    c = np.zeros((8, 2), bool)
    c[2:6, 0] = True
    c[1:4, 1] = True
    c[5:7, 1] = True                       # a run reaching the last two columns: the whole step
    f = leading_edge_factor(c, 2)
    assert f[:, 0].tolist() == [0, 0, 1, 1, 1, 0.5, 0, 0]
    assert f[:, 1].tolist() == [0, 1, 1, 0.5, 0, 1, 1, 0]
    assert np.array_equal(leading_edge_factor(c, 1), c.astype(float))
