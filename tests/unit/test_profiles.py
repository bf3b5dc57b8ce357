"""Profiles: reading (CSV, CONTACT .prw/.prr), checks with clear errors, and the smoothing spline."""
import math

import numpy as np
import pytest

from conformal.errors import InputError
from conformal.geometry.placement import place_rail
from conformal.geometry.profiles import BUILTIN, builtin_dir, check_points, load_profile, read_points
from conformal.geometry.spline import fit_curve
from _paths import SCENES



def test_builtin_files_are_packaged_and_load():
    for name, entry in BUILTIN.items():
        assert (builtin_dir() / entry.file).is_file(), name
        p = load_profile(name, entry.kind)
        assert p.points.shape[0] > 100 and p.points[0, 0] < p.points[-1, 0]


def test_raw_contact_s1002_equals_analytic_s1002():
    # README: the CONTACT Manchester file (y mirrored) equals the analytic S1002 to 1.6e-6 mm at its
    # points.  Between them (up to 1.7 mm apart) the interpolating spline cannot follow the jumps
    # of curvature of the flange flank (line -> R13 arc): 3e-4 mm there, 2 orders below the
    # approach of a loaded contact (~0.02 mm); elsewhere below 1e-5 mm.
    raw = fit_curve(load_profile("S1002_MBENCH", "wheel").points, smoothing=0.0)
    ana = load_profile("S1002", "wheel").points
    inside = (ana[:, 0] > -59.5) & (ana[:, 0] < 59.5)
    s = raw.project(ana[inside], np.interp(ana[inside, 0], raw.points[:, 0], raw.s_points))
    d = np.linalg.norm(raw.point(s) - ana[inside], axis=1)
    assert d.max() < 3e-4
    assert np.median(d) < 1e-6


def test_uic60_rotated_by_cant_equals_contact_canted_rail():
    # README: uic60_head_r300w21 rotated by 0.024995 rad matches CONTACT's canted Manchester rail to
    # 3e-5 mm.  Placing both on the track (lowered to z = 0, gauge face 717.5 mm from the centre)
    # must make them coincide: this checks the sense of the cant rotation and the gauge rule.
    a = place_rail(fit_curve(load_profile("UIC60", "rail").points, 1.0), cant=0.024995,
                   placement="wheelset", gauge=1435.0, gauge_height=14.0)
    b = place_rail(fit_curve(load_profile("UIC60_MBENCH_1IN40", "rail").points, 1.0), cant=0.0,
                   placement="wheelset", gauge=1435.0, gauge_height=14.0)
    s, pb = b.sample(0.5)
    keep = (pb[:, 1] < 30.0)        # the head (the canted file reaches lower on one side)
    sa = a.project(pb[keep], a.curve.length * 0.5 + (s[keep] - b.curve.length * 0.5))
    d = np.linalg.norm(a.point(sa) - pb[keep], axis=1)
    assert d.max() < 2e-3           # 3e-5 (file fit) + smoothing-spline error at the arc junctions
    assert b.origin[0] == pytest.approx(760.533, abs=0.005)   # CONTACT's results imply 760.533 mm


def test_smoothing_spline_curvatures_of_rail_arcs():
    # UIC 60 head: R300 on |y| < 10.5, R80 to |y| = 25.99, R13 to the 1:20 flank at |y| = 36.
    c = fit_curve(load_profile("UIC60", "rail").points, smoothing=1.5)
    for y, radius, tol in ((0.0, 300.0, 0.02), (5.0, 300.0, 0.02), (18.0, 80.0, 0.01), (31.0, 13.0, 0.01)):
        k = float(c.curvature(c.s_at_y(y)))
        assert 1.0 / k == pytest.approx(radius, rel=tol), y
    assert c.smoothing_error < 1e-4 and c.smoothing_rms < c.smoothing_error
    # arc length parametrisation: |c'(s)| = 1 everywhere
    s = np.linspace(0.0, c.length, 5000)
    assert np.allclose(np.hypot(c.y(s, 1), c.z(s, 1)), 1.0, atol=1e-6)


def test_smoothing_reduces_noise_and_reports_its_error():
    # an R100 arc sampled every 0.1 mm with 0.2 um measurement noise: interpolation turns the noise
    # into curvature errors 30 times 1/R; a 10 mm smoothing wavelength brings them below 5 % of 1/R
    # and reports an rms distance of the points from the curve of about the noise
    rng = np.random.default_rng(1)
    t = np.linspace(-0.3, 0.3, 600)
    noise = 2e-4
    noisy = np.c_[100 * np.sin(t), 100 * (1 - np.cos(t))] + rng.normal(scale=noise, size=(600, 2))
    rough = fit_curve(noisy, smoothing=0.0)
    smooth = fit_curve(noisy, smoothing=10.0)
    s = np.linspace(5.0, rough.length - 5.0, 500)
    assert np.abs(rough.curvature(s) - 0.01).max() > 0.1
    assert np.abs(smooth.curvature(s) - 0.01).max() < 5e-4
    assert 0.5 * noise < smooth.smoothing_rms < 2 * noise
    assert rough.smoothing_error < 1e-5


def test_own_smoothing_spline_is_scipys_and_interpolates_at_zero_smoothing():
    """spline.smoothing_spline (the penalty matrix in array operations) gives the coefficients of
    scipy's make_smoothing_spline (a Python loop per point) on profiles and uneven noisy data,
    to 1e-13 of the data's size (bitwise with the scipy it was written against), for y of one
    and two columns; lam = 0 interpolates the points (an independent property)."""
    from scipy.interpolate import make_smoothing_spline

    from conformal.geometry.spline import _chord_parameter, smoothing_spline

    rng = np.random.default_rng(3)
    x = np.cumsum(rng.uniform(0.05, 0.4, 300))
    data = [(x, np.c_[np.sin(x), np.cos(0.3 * x)] + rng.normal(scale=0.01, size=(300, 2)))]
    for spec, kind in (("S1002_MBENCH", "wheel"), ("UIC60", "rail")):
        p = load_profile(spec, kind).points
        data.append((_chord_parameter(p), p))
    for t, y in data:
        scale = np.abs(y).max()
        for lam in (1e-6, 1e-3, 0.5, 20.0):
            for yy in (y, y[:, 1]):
                ours, theirs = smoothing_spline(t, yy, lam), make_smoothing_spline(t, yy, lam=lam)
                assert ours.c.shape == theirs.c.shape and np.array_equal(ours.t, theirs.t)
                assert np.abs(ours.c - theirs.c).max() <= 1e-13 * scale
    t, y = data[0]
    assert np.abs(smoothing_spline(t, y, 0.0)(t) - y).max() < 1e-9
    with pytest.raises(ValueError):
        smoothing_spline(t[::-1], y, 1.0)


def test_simpack_prw_file(tmp_path):
    # a tiny CONTACT/SIMPACK wheel file: header block with mirror.y = 1 and mm units, '!' comments
    ys = np.linspace(-20.0, 20.0, 41)
    zs = 0.001 * ys ** 2
    text = "\n".join(["! test wheel, z = y^2/1000", "header.begin", "  version = 1", "  units.len.f = 1000",
                      "  mirror.y = 1   ! y is stored the other way round", "header.end",
                      "point.begin"] + [f"  {-y:.7E} {z:.7E}" for y, z in zip(ys, zs)] + ["point.end"])
    f = tmp_path / "tiny.prw"
    f.write_text(text)
    p = read_points(f)
    assert p.shape == (41, 2) and np.allclose(p[:, 0], ys)
    c = fit_curve(check_points(p, "wheel", "tiny"), 0.0)
    assert float(c.curvature(c.length / 2)) == pytest.approx(0.002, rel=1e-5)   # 8 digits in the file


def _write(tmp_path, name, rows):
    f = tmp_path / name
    f.write_text("# y,z\n" + "\n".join(f"{y},{z}" for y, z in rows))
    return f


def test_nan_is_rejected_with_the_line(tmp_path):
    f = _write(tmp_path, "nan.csv", [(0, 0), (1, 0.1), (2, float("nan")), (3, 0.3), (4, 0.4), (5, 0.5)])
    with pytest.raises(InputError, match=r"nan.csv: line 4: NaN"):
        read_points(f)


def test_too_few_points(tmp_path):
    f = _write(tmp_path, "few.csv", [(0, 0), (1, 0.1), (2, 0.2)])
    with pytest.raises(InputError, match="too few points"):
        check_points(read_points(f), "rail", "few.csv")


def test_self_intersection(tmp_path):
    # a bow tie: the curve crosses itself
    rows = [(0, 0), (2, 0), (4, 1), (5, 3), (4, 4), (3, 3), (3.5, 0.5), (6, 0), (8, 0)]
    with pytest.raises(InputError, match="intersects itself"):
        check_points(np.array(rows, float), "rail", "bowtie")


def test_crossing_search_by_sorted_ranges_finds_the_pairwise_first_crossing():
    """_segments_cross (pairs from the segments sorted by y) returns the first crossing pair (least
    i, then j) of the all-pairs test on random polylines (many crossings), monotone ones with one
    point moved back (one or two), on a quarter-mm lattice (ties, shared ends, collinear
    segments) and on the built-in profiles (none)."""
    from conformal.geometry.profiles import _segments_cross, _segments_cross_pairwise

    rng = np.random.default_rng(0)
    found = 0
    for trial in range(600):
        n = int(rng.integers(2, 60))
        if trial % 3 == 0:
            p = rng.random((n, 2))
        elif trial % 3 == 1:
            p = np.c_[np.cumsum(rng.random(n)), rng.normal(scale=0.3, size=n)]
            if n > 5:
                p[n // 2] = p[1] + rng.normal(scale=0.5, size=2)
        else:
            p = np.round(rng.random((n, 2)) * 4) / 4
        first = _segments_cross(p)
        assert first == _segments_cross_pairwise(p)
        found += first is not None
    assert found > 300
    for name in ("S1002", "UIC60"):
        entry = BUILTIN[name]
        assert _segments_cross(load_profile(name, entry.kind).points) is None


def test_points_out_of_order():
    rows = np.array([(0, 5), (1, 3), (2, 1), (3, 0), (1.5, 0.1), (4, 1), (5, 3), (6, 5)], float)
    with pytest.raises(InputError, match="out of order"):
        check_points(rows, "rail", "zigzag")


def test_rail_upside_down():
    """A rail head with z positive upwards looks like a groove rail (z downwards): both are accepted
    (issue 11: CONTACT's groove rails were refused), with a warning that names [geometry] rail_z;
    rail_z = "up" reads such a file back into the head."""
    from conformal.geometry.profiles import rail_orientation_warning

    head = load_profile("UIC60", "rail").points
    p = head * np.array([1.0, -1.0])   # z positive upwards
    checked = check_points(p, "rail", "flipped")
    assert "rail_z" in rail_orientation_warning(checked, "flipped")
    assert rail_orientation_warning(head, "UIC60") is None
    groove = np.loadtxt(SCENES / "groove_rail_r10p02.csv", delimiter=",")
    inner = groove[np.abs(groove[:, 0]) <= 10.0]          # the groove and its shoulders only
    assert "groove" in rail_orientation_warning(check_points(inner, "rail", "groove"), "groove")


def test_profiles_with_z_upwards_are_read_with_the_key(tmp_path):
    f = tmp_path / "uic60_up.csv"
    np.savetxt(f, load_profile("UIC60", "rail").points * np.array([1.0, -1.0]), delimiter=",")
    back = load_profile(str(f), "rail", z_up=True).points
    assert np.allclose(back, load_profile("UIC60", "rail").points)
    w = tmp_path / "s1002_up.csv"
    np.savetxt(w, load_profile("S1002", "wheel").points * np.array([1.0, -1.0]), delimiter=",")
    with pytest.raises(InputError, match="wheel_z"):
        load_profile(str(w), "wheel")
    assert np.allclose(load_profile(str(w), "wheel", z_up=True).points, load_profile("S1002", "wheel").points)


def test_wheel_upside_down():
    p = load_profile("S1002", "wheel").points * np.array([1.0, -1.0])
    with pytest.raises(InputError, match="upside down"):
        check_points(p, "wheel", "flipped")


def test_unknown_profile_and_missing_block(tmp_path):
    with pytest.raises(InputError, match="neither a built-in name"):
        load_profile("S1003", "wheel")
    f = tmp_path / "empty.prr"
    f.write_text("header.begin\nheader.end\n")
    with pytest.raises(InputError, match="point.begin"):
        read_points(f)
    with pytest.raises(InputError, match="is a rail profile"):
        load_profile("UIC60", "wheel")


def test_reversed_order_is_normalised():
    p = load_profile("UIC60", "rail").points
    q = check_points(p[::-1], "rail", "reversed")
    assert np.array_equal(p, q)
    assert math.isclose(fit_curve(q).length, fit_curve(p).length, rel_tol=1e-12)


def test_gauss_rule_of_the_arc_length_is_numpys():
    """fit_curve's 4-point Gauss-Legendre rule (constants) is bitwise numpy's leggauss(4)."""
    from conformal.geometry.spline import GAUSS4

    g, w = np.polynomial.legendre.leggauss(4)
    assert np.array_equal(np.array(GAUSS4[0]), g) and np.array_equal(np.array(GAUSS4[1]), w)


def test_csv_rows_read_by_numpy_equal_the_row_by_row_reading(tmp_path):
    """The C parser of comma-separated rows (profiles._rows_fast) gives bitwise the points of the
    row-by-row reading (Python's float) on every built-in profile and on rows with comments, blank
    lines and spaces; anything else (another separator, a header, a third column, an empty field,
    a non-finite value, no rows) is left to the row-by-row reading and its messages."""
    from conformal.geometry import profiles as pr

    rng = np.random.default_rng(5)
    texts = [(builtin_dir() / e.file).read_text() for e in BUILTIN.values()]
    texts.append("# c\n" + "\n".join(f" {float(y)!r} , {float(z)!r}  # note" if i % 7 == 0 else f"{float(y)!r},{float(z)!r}"
                                     for i, (y, z) in enumerate(rng.normal(scale=50.0, size=(200, 2)))) + "\n\n")
    texts.append("\n".join(f"{y:.17g},{z:.6E}" for y, z in rng.uniform(-1e3, 1e3, size=(50, 2))))
    for text in texts:
        lines = text.splitlines()
        fast = pr._rows_fast(lines)
        rows = [ln.split("#")[0].strip() for ln in lines]
        ref = np.array([[float(v) for v in r.split(",")] for r in rows if r])
        assert fast is not None and fast.shape == ref.shape and np.array_equal(fast, ref)
        assert np.array_equal(np.signbit(fast), np.signbit(ref))
    for text in ("y,z\n1,2\n3,4", "1 2\n3 4", "1;2\n3;4", "1,2,3\n4,5,6", "1,,2\n3,4", "1,2,\n3,4",
                 "nan,1\n2,3", "1,inf\n2,3", "# only a comment", "", "1_0,2\n3,4", "0x10,1\n2,3"):
        assert pr._rows_fast(text.splitlines()) is None, text
    f = tmp_path / "semi.csv"
    f.write_text("# y;z\n" + "\n".join(f"{y};{0.01 * y * y}" for y in range(-10, 11)))
    assert np.array_equal(read_points(f)[:, 1], [0.01 * y * y for y in range(-10, 11)])
