"""Kalker's creep coefficients: the table, its interpolation, the slender-ellipse asymptotes and C33."""
import csv
import math

import numpy as np
import pytest
from scipy.integrate import quad

from conformal.errors import ConformalError, InputError
from conformal.theories import coefficients as coef

ROWS = [r for r in csv.DictReader(ln for ln in coef.TABLE_FILE.read_text().splitlines()
                                  if ln.strip() and not ln.startswith("#"))]


def a_over_b(branch, g):
    return g if branch == "a<=b" else 1.0 / g


def test_table_is_complete_and_monotone():
    """60 rows; every sequence in a/b is monotone (C grows as the ellipse gets longer in x),
    except C11 at nu = 0.5 for a <= b, which has a shallow minimum (4.85, 4.81, 4.80, 4.82 ...:
    its a/b -> 0 limit pi²/2 = 4.93 lies above the circle's trend).  This catches CONTACT's
    transcription error C23(a<=b, 0.8, 0.25) = 1.15 (correct: 1.25)."""
    assert len(ROWS) == 60
    row = [r for r in ROWS if r["branch"] == "a<=b" and float(r["g"]) == 0.8 and float(r["nu"]) == 0.25][0]
    assert float(row["C23"]) == 1.25
    for branch in ("a<=b", "a>b"):
        for nu in (0.0, 0.25, 0.5):
            rs = sorted((r for r in ROWS if r["branch"] == branch and float(r["nu"]) == nu),
                        key=lambda r: a_over_b(branch, float(r["g"])))
            for name in ("C11", "C22", "C23"):
                v = np.array([float(r[name]) for r in rs])
                if name == "C11" and nu == 0.5 and branch == "a<=b":
                    assert np.all(np.diff(v)[3:] > 0) and v.min() == 4.80
                    continue
                assert np.all(np.diff(v) > 0), (branch, nu, name, v)
    # both branches meet at the circle, and C11 = C22 at nu = 0 (Kalker's table)
    for nu in ("0", "0.25", "0.5"):
        at1 = [r for r in ROWS if float(r["g"]) == 1.0 and r["nu"] == nu]
        assert at1[0]["C11"] == at1[1]["C11"] and at1[0]["C23"] == at1[1]["C23"]
    assert all(r["C11"] == r["C22"] for r in ROWS if float(r["nu"]) == 0.0)


def test_interpolation_reproduces_every_node():
    r = np.array([a_over_b(x["branch"], float(x["g"])) for x in ROWS])
    nu = np.array([float(x["nu"]) for x in ROWS])
    c11, c22, c23 = coef.coefficient_arrays(r, nu)
    for name, c in (("C11", c11), ("C22", c22), ("C23", c23)):
        ref = np.array([float(x[name]) for x in ROWS])
        np.testing.assert_allclose(c, ref, rtol=1e-12)
    c = coef.kalker_coefficients(2.0, 0.25)
    assert (c.C11, c.C22, c.C23) == pytest.approx((5.1, 4.9, 2.62), rel=1e-13) and c.source == "table"


def test_interpolation_error_leave_every_other_node_out():
    """The spline in ln(a/b) built on every other node predicts the left-out nodes within
    1.5 % (measured max 1.5 %); on the full table the spacing is half, so the interpolation
    error between nodes is about 4x smaller (cubic: O(h^4) in ln C away from the ends)."""
    tab = coef.kalker_table()
    keep = np.zeros(len(tab.t), bool)
    keep[::2] = True
    keep[-1] = True
    half = coef._Table(tab.names, tab.t[keep], tab.nu, tab.values[:, :, keep])
    t_out = tab.t[~keep]
    for j, nu in enumerate(tab.nu):
        pred = coef._interp_table(half, t_out, np.full(t_out.shape, nu))
        err = pred / tab.values[:, j, ~keep] - 1
        assert np.abs(err).max() < 0.016, (nu, err)


def test_nu_interpolation_matches_contact_flexibility_coefficients():
    """tractcurv (a/b = 0.5, nu = 0.28): CONTACT prints the FASTSIM flexibilities L1, L2, L3 =
    5.491, 6.773, 4.526e-5 mm³/N from its own coefficient evaluation.  Seed Eq. 27 with our
    quadratic-in-nu interpolation reproduces them within 0.2 % (linear in nu: L1 0.8 % off)."""
    a, b, G = 6.3036, 12.6072, 82000.0
    c = coef.kalker_coefficients(a / b, 0.28)
    assert 8 * a / (3 * G * c.C11) == pytest.approx(5.491e-5, rel=2e-3)
    assert 8 * a / (3 * G * c.C22) == pytest.approx(6.773e-5, rel=2e-3)
    assert math.pi * a * math.sqrt(a / b) / (4 * G * c.C23) == pytest.approx(4.526e-5, rel=2e-3)


def test_interpolated_values_are_monotone_between_nodes():
    r = np.exp(np.linspace(math.log(0.1), math.log(10.0), 400))
    for nu in (0.0, 0.1, 0.28, 0.4, 0.5):
        c11, c22, c23 = coef.coefficient_arrays(r, nu)
        assert np.all(np.diff(c22) > 0) and np.all(np.diff(c23) > 0)
        # C11: monotone where the table is (nu <= 0.25 nodes); at high nu it has the minimum
        assert np.all(np.diff(c11) > 0) if nu <= 0.28 else np.all(np.diff(c11[r > 0.45]) > 0)
    # and in nu at fixed a/b (the table grows with nu for every coefficient)
    nus = np.linspace(0.0, 0.5, 51)
    for ratio in (0.13, 0.5, 1.0, 3.3, 8.0):
        c11, c22, c23 = coef.coefficient_arrays(ratio, nus)
        assert np.all(np.diff(c11) > 0) and np.all(np.diff(c23) > 0) and np.all(np.diff(c22) >= 0)


@pytest.mark.parametrize("nu", [0.0, 0.25, 0.5])
def test_asymptotes_join_the_table(nu):
    """Published slender-ellipse asymptotes vs the table at the edge g = 0.1, and convergence:
    every asymptote is closer to the table at g = 0.1 than at g = 0.2 (an O(g) remainder).
    Measured at g = 0.1: C11, C22 within 4.3 %, C23 (b/a) within 1 %, C23 (a/b) within 6 %."""
    bounds = {"a<=b": (0.02, 0.025, 0.065), "a>b": (0.045, 0.045, 0.011)}
    for branch, tol in bounds.items():
        errs = []
        for g in (0.1, 0.2):
            r = a_over_b(branch, g)
            tab = np.array([float(x[n]) for x in ROWS if x["branch"] == branch and float(x["g"]) == g
                            and float(x["nu"]) == nu for n in ("C11", "C22", "C23")])
            asym = np.array([float(v) for v in coef.asymptotic_coefficients(r, nu)])
            errs.append(np.abs(asym / tab - 1))
        assert np.all(errs[0] <= np.array(tol)), (branch, errs[0])
        assert np.all(errs[0] < errs[1]), (branch, errs)


def test_beyond_the_table_continuous_and_asymptotic():
    for nu in (0.0, 0.28, 0.5):
        for edge, step in ((0.1, -1e-9), (10.0, 1e-8)):
            inside = np.array(coef.coefficient_arrays(edge, nu))
            outside = np.array(coef.coefficient_arrays(edge + step, nu))
            np.testing.assert_allclose(outside, inside, rtol=1e-6)
        # far out the blend is the published asymptote (correction (r - 1) g/0.1 -> 0)
        for r in (1e-3, 1e3):
            np.testing.assert_allclose(coef.coefficient_arrays(r, nu),
                                       coef.asymptotic_coefficients(r, nu), rtol=0.01 * 0.07)
    assert coef.kalker_coefficients(0.05, 0.28).source == "asymptote"
    assert coef.kalker_coefficients(20.0, 0.28).source == "asymptote"


def test_line_contact_limit_from_carter_strip_theory():
    """a/b -> 0: each strip y is a 2-D rolling contact of half-width a(y) = a sqrt(1 - y²/b²)
    with Carter's small-creepage force per unit width F' = -pi G a(y) xi / (2(1 - nu)).
    Integrated numerically over the ellipse this gives C11 = pi²/(4(1-nu)) and, with the local
    creepage xi = -phi y, C33 = pi²/(16(1-nu) g) (g = a/b): the published leading terms."""
    G, nu, a, b = 1.0, 0.3, 0.01, 1.0
    strip = lambda y: math.pi * G * a * math.sqrt(1 - (y / b) ** 2) / (2 * (1 - nu))  # noqa: E731
    FX = -quad(strip, -b, b)[0] * 1.0                       # xi = 1
    MZ = -quad(lambda y: y * strip(y) * y, -b, b)[0]        # px = +strip*phi*y, MZ = -int y px
    c11 = -FX / (G * a * b)
    c33 = -MZ / (G * (a * b) ** 2)
    assert c11 == pytest.approx(float(coef.asymptotic_coefficients(a / b, nu)[0]), rel=1e-10)
    assert c33 == pytest.approx(float(coef.asymptotic_c33(a / b, nu)), rel=1e-10)


def test_bad_input():
    with pytest.raises(InputError, match="nu"):
        coef.kalker_coefficients(1.0, 0.6)
    with pytest.raises(InputError, match="nu"):
        coef.kalker_coefficients(1.0, -0.1)
    with pytest.raises(InputError, match="a/b"):
        coef.kalker_coefficients(0.0, 0.3)


def test_c33_needs_the_exact_solver_table(tmp_path):
    with pytest.raises(ConformalError, match="exact solver"):
        coef.c33(1.0, 0.28, path=tmp_path / "kalker_c33.csv")


def test_c33_reads_a_table(tmp_path):
    """With a C33 table (here a synthetic one in the csv format the exact solver writes) c33
    reproduces its nodes, interpolates in nu, and refuses a/b beyond it."""
    f = tmp_path / "kalker_c33.csv"
    lines = ["branch,g,nu,C33"]
    vals = {}
    for branch in ("a<=b", "a>b"):
        for g in (0.2, 0.4, 0.6, 0.8, 1.0):
            if branch == "a>b" and g < 0.6:
                continue
            for nu in (0.0, 0.25, 0.5):
                v = (1.0 + nu) / a_over_b(branch, g) ** 0.8
                vals[(a_over_b(branch, g), nu)] = v
                lines.append(f"{branch},{g},{nu},{v:.12g}")
    f.write_text("\n".join(lines) + "\n")
    for (r, nu), v in vals.items():
        assert coef.c33(r, nu, path=f) == pytest.approx(v, rel=1e-10)
    # (1 + nu) is linear in nu: quadratic interpolation in nu is exact for it
    assert coef.c33(0.4, 0.1, path=f) == pytest.approx(1.1 / 0.4**0.8, rel=1e-10)
    with pytest.raises(ConformalError, match="beyond"):
        coef.c33(3.0, 0.25, path=f)
    # below the table: the a/b -> 0 asymptote, blended continuously
    assert coef.c33(0.2 - 1e-9, 0.25, path=f) == pytest.approx(coef.c33(0.2, 0.25, path=f), rel=1e-6)
