"""Contact search (seed Eqs. 54-56): analytic cases, a brute-force check, several minima, hard cases."""
import math

import numpy as np
import pytest

from conformal.errors import NoContactError
from conformal.geometry.patches import find_patches
from conformal.geometry.placement import make_pair
from conformal.geometry.profiles import load_profile
from conformal.geometry.search import RailTop, find_contacts, touch_height
from conformal.geometry.spline import fit_curve

Y = np.linspace(-30.0, 30.0, 601)
CONE = fit_curve(np.c_[Y, -Y / 40.0], 0.0, "cone 1:40")                       # conical wheel, radius 460
R300 = fit_curve(np.c_[Y, 300.0 - np.sqrt(300.0 ** 2 - Y ** 2)], 0.0, "R300")  # rail crown arc
S1002 = fit_curve(load_profile("S1002_MBENCH", "wheel").points, 1.0)
UIC60_C = fit_curve(load_profile("UIC60_MBENCH_1IN40", "rail").points, 1.0)
UIC60 = fit_curve(load_profile("UIC60", "rail").points, 1.0)
GAMMA = math.atan(1 / 40)


def single(wheel, rail, shift=0.0, roll=0.0, yaw=0.0, cant=0.0):
    return make_pair(wheel, rail, side="right", placement="single", lateral_shift=shift, roll=roll, yaw=yaw,
                     rail_cant=cant, gauge=1435.0, gauge_height=14.0, flange_back=1360.0,
                     flange_back_pos=None, wheel_radius=460.0)


def mbench(side, y, yaw, roll):
    return make_pair(S1002, UIC60_C, side=side, placement="wheelset", lateral_shift=y, roll=roll, yaw=yaw,
                     rail_cant=0.0, gauge=1435.0, gauge_height=14.0, flange_back=1360.0,
                     flange_back_pos=-70.0, wheel_radius=460.0)


@pytest.mark.parametrize("roll", [0.0, 0.01])
def test_cone_on_circular_crown(roll):
    """A 1:40 cone rolled by phi touches an R300 crown where the slopes agree:
    y = -R sin(gamma - phi), contact angle -(gamma - phi); Hertz B = 1/(2R) and A = cos(gamma)/(2 rho)
    (Meusnier: the normal makes the cone angle gamma with the wheel's radius, whatever the roll)."""
    z, sr = touch_height(single(CONE, R300, roll=roll))
    c = sr.contacts[0]
    g = GAMMA - roll
    assert c.rail_point[1] == pytest.approx(-300.0 * math.sin(g), abs=1e-6)
    assert c.delta == pytest.approx(-g, abs=1e-8)
    assert abs(c.penetration) < 1e-9 and c.residual < 1e-8
    A, B, angle = c.principal()
    assert B == pytest.approx(1.0 / 600.0, rel=1e-6)
    assert A == pytest.approx(math.cos(GAMMA) / (2 * c.rolling_radius), rel=1e-6)
    if roll == 0.0:   # height: rail z = R(1 - cos gamma) equals wheel z = z_ws - y_w / 40
        assert z == pytest.approx(300.0 * (1 - math.cos(g)) - 300.0 * math.sin(g) / 40.0, abs=1e-8)


def test_yawed_cone_contact_locus():
    """With yaw psi the contact leaves the wheel's bottom: sin(theta) = tan(psi)/40 on the locus,
    so x = sin(psi) (rho/40 - u), u the axial position of the contact circle."""
    psi = 0.02
    _, sr = touch_height(single(CONE, R300, yaw=psi))
    c = sr.contacts[0]
    assert math.sin(c.theta) == pytest.approx(math.tan(psi) / 40.0, rel=1e-6)
    assert c.x == pytest.approx(math.sin(psi) * (c.rolling_radius / 40.0 - c.y_wheel), rel=1e-6)
    assert c.x == pytest.approx(0.380, abs=2e-3)


def test_newton_point_agrees_with_brute_force_minimum():
    """Yawed and rolled S1002 in flange contact (Manchester 8 mm): the Newton-Raphson contact point
    is the minimum of the vertical gap over a dense (s_w, theta) sampling of the wheel surface."""
    pair = mbench("right", 8.0, 0.0192, -0.008606)
    z, sr = touch_height(pair)
    c = sr.contacts[0]
    wheel, top = pair.wheel(z), RailTop.of(pair.rail)
    s = c.s_w + np.linspace(-1.0, 1.0, 401)
    th = c.theta + np.linspace(-4e-3, 4e-3, 401)
    S, T = np.meshgrid(s, th, indexing="ij")
    P = wheel.point(S, T)
    gap = top.z_at(P[..., 1]) - P[..., 2]
    k = np.unravel_index(np.nanargmin(gap), gap.shape)
    assert np.nanmin(gap) > -2e-6                         # nothing of the wheel lies inside the rail
    assert P[k][0] == pytest.approx(c.x, abs=0.05)        # grid steps: 0.005 mm in s, 0.0019 mm in x
    assert P[k][1] == pytest.approx(c.wheel_point[1], abs=0.02)
    assert math.degrees(-c.delta) == pytest.approx(54.4, abs=0.1)   # CONTACT: -0.9501 rad


def test_flange_flank_at_70_degrees():
    """S1002's flange flank is a straight line of slope 2.747477419 (section E, README): on a 1:20
    canted UIC 60 the flank meets the rail's R13 corner at exactly atan(2.7475) = 70.0 degrees."""
    _, sr = touch_height(single(S1002, UIC60, shift=5.0, cant=math.atan(1 / 20)))
    c = sr.contacts[0]
    assert -39.764 < c.y_wheel < -38.427                   # on the straight flank
    assert c.delta == pytest.approx(-math.atan(2.747477419), abs=2e-4)


def test_synthetic_flank_at_75_degrees():
    """A wheel with a straight 75-degree flank on the UIC 60 R13 gauge corner: the contact angle is
    75 degrees, the rail point lies where the R13 arc has that inclination, and the wheel rises by
    tan(75) per mm of lateral shift."""
    yt, yf = np.arange(-10.0, 40.001, 0.1), np.arange(-18.0, -10.0, 0.1)
    t = math.tan(math.radians(75.0))
    wheel = fit_curve(np.r_[np.c_[yf, -(yf + 10) * t], np.c_[yt, 0 * yt]], 1.0, "flank75")
    z1, s1 = touch_height(single(wheel, UIC60, shift=-21.0))
    z2, s2 = touch_height(single(wheel, UIC60, shift=-20.0))
    c = s1.contacts[0]
    assert math.degrees(c.delta) == pytest.approx(-75.0, abs=1e-3)
    # R13 centre (-23.0162, 14.9089) (README): the 75-degree point is centre + 13 (-sin 75, -cos 75)
    assert c.rail_point[1] == pytest.approx(-23.0162 - 13 * math.sin(math.radians(75)), abs=2e-3)
    assert (z2 - z1) == pytest.approx(-t, rel=1e-4)
    assert c.principal()[1] == pytest.approx(1 / 26.0, rel=2e-3)   # B = 1/(2 x 13), flank straight


def test_global_search_finds_tread_and_gauge_corner():
    """Manchester right wheel at 5 mm: two local minima of the gap (tread near y_r = -23.7 and gauge
    corner near -33.9); both are refined and the gauge corner touches first (CONTACT: -33.4)."""
    pair = mbench("right", 5.0, 0.012, -0.0003554)
    z, sr = touch_height(pair)
    ys = [float(pair.rail.to_own(c.rail_point[1:])[0]) for c in sr.contacts]
    assert len(sr.contacts) >= 2
    assert ys[0] == pytest.approx(-33.95, abs=0.1) and abs(sr.contacts[0].penetration) < 1e-9
    assert any(abs(y + 23.7) < 0.3 for y in ys[1:])
    tread = [c for c, y in zip(sr.contacts, ys) if abs(y + 23.7) < 0.3][0]
    assert 0.01 < tread.gap < 0.04                          # CONTACT's loaded approach is 0.027


def test_two_point_contact_between_4_5_and_5_mm():
    """The contact jumps from the tread to the gauge corner between 4.5 and 5 mm (CONTACT); at the
    shift where both touch, the search returns two touching points."""
    def gap_difference(y):
        pair = mbench("right", y, 0.0024 * y, -0.0003554)
        _, sr = touch_height(pair)
        ys = [float(pair.rail.to_own(c.rail_point[1:])[0]) for c in sr.contacts]
        corner = [c for c, yr in zip(sr.contacts, ys) if yr < -30]
        tread = [c for c, yr in zip(sr.contacts, ys) if yr > -30]
        return tread[0].penetration - corner[0].penetration, sr

    lo, hi = 4.5, 5.0
    assert gap_difference(lo)[0] > 0 > gap_difference(hi)[0]
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if gap_difference(mid)[0] > 0:
            lo = mid
        else:
            hi = mid
    d, sr = gap_difference(lo)
    touching = [c for c in sr.contacts if c.penetration > -1e-6]
    assert len(touching) == 2 and abs(d) < 1e-6
    assert touching[0].delta - touching[1].delta == pytest.approx(0.29 - 0.12, abs=0.03) or \
        touching[1].delta - touching[0].delta == pytest.approx(0.29 - 0.12, abs=0.03)


def test_lifted_wheel_reports_the_gap():
    """Lifting the touching wheel by 0.05 mm opens a normal gap of 0.05 cos(delta) (seed Eq. 56)."""
    pair = mbench("right", 0.0, 0.0, 0.0)
    z, sr = touch_height(pair)
    with pytest.raises(NoContactError, match=r"wheel lifted off: the smallest gap between wheel and rail is") as e:
        find_patches(pair.wheel(z - 0.05), pair.rail)
    gap = float(str(e.value).split(" is ")[1].split()[0])
    assert gap == pytest.approx(0.05 * math.cos(sr.contacts[0].delta), abs=1e-5)


def test_candidates_are_distinct_minima():
    pair = mbench("left", 0.0, 0.0, 0.0)
    z, _ = touch_height(pair)
    sr = find_contacts(pair.wheel(z), pair.rail)
    pens = [c.penetration for c in sr.contacts]
    assert pens == sorted(pens, reverse=True)
    s = sorted(c.s_w for c in sr.contacts)
    assert np.all(np.diff(s) > 0.05)


def test_flange_tip_running_in_a_deep_groove():
    """Single wheel on a grooved rail (test rig / tram, placement "single"): the groove bottom lies
    20 mm below the head, less than S1002's 28 mm flange height, so the wheel runs on its flange
    tip: lifted by 28 - 20 = 8 mm, contact at the tip (y_w = -55, R12 arc apex), rolling radius
    460 + 28, contact angle 0, whatever the shift within the groove."""
    guard = np.c_[np.linspace(-95, -80, 76), np.zeros(76)]
    wall1 = np.c_[np.linspace(-80, -72, 101)[1:], np.linspace(0, 20, 101)[1:]]
    bottom = np.c_[np.linspace(-72, -40, 161)[1:], np.full(160, 20.0)]
    wall2 = np.c_[np.linspace(-40, -28, 101)[1:], np.linspace(20, 28 ** 2 / 600, 101)[1:]]
    yh = np.linspace(-28, 28, 281)[1:]
    flank = np.c_[np.linspace(28, 30, 51)[1:], np.linspace(28 ** 2 / 600, 20, 51)[1:]]
    from conformal.geometry.profiles import check_points
    groove = fit_curve(check_points(np.r_[guard, wall1, bottom, wall2, np.c_[yh, yh ** 2 / 600], flank],
                                    "rail", "groove"), 1.0, "groove")
    wheel = fit_curve(load_profile("S1002", "wheel").points, 1.0)
    for shift in (-2.0, 2.0):
        z, sr = touch_height(single(wheel, groove, shift=shift))
        c = sr.contacts[0]
        assert z == pytest.approx(-8.0, abs=1e-3)
        assert c.y_wheel == pytest.approx(-55.0, abs=0.01) and c.rolling_radius == pytest.approx(488.0, abs=1e-3)
        assert abs(c.delta) < 1e-4 and c.rail_point[1] == pytest.approx(-55.0 + shift, abs=0.01)
