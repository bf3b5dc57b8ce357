"""The worn example and the placement's warnings (issue 11, item 4).

The worn pair (CONTACT's high-mileage wheel on the worn "site B" high rail) stood at a lateral
shift of 17 mm: the wheelset lifted 13.7 mm, contact 0.5 mm from the flange tip, pmax 5854 N/mm²
and no warning.  Both the example and the placement were wrong:

* the wheelset roll is a root of z_right(roll) - z_left(roll) = 0, which has several roots once a
  flange is at its rail (the wheelset on tread and flange root near zero roll, and the flange tip
  lifted onto the rail at -14 mrad); the bracket let Brent's method pick either, and the height
  jumped by 11.4 mm between 15.370 and 15.375 mm of shift.  The root nearest to the zero-roll
  estimate is now taken: the height is continuous up to 15.5 mm (tread and flange root touch);
* beyond 15.5 mm no state of the wheelset on its tread exists at a prescribed shift: the flange
  tip sits on the rail (12 mm higher).  17 mm is such a state; the example now uses 15.5 mm, and
  the placement warns of contact at the flange tip or a profile end, and of a lifted wheelset.
"""

import numpy as np
import pytest

from conformal.geometry.spline import fit_curve, kinks
from conformal.geometry.sweep import jump_warnings, sweep
from conformal.geometry.wheelrail import wheelset_roll
from conformal.scene import load_scene, scene_from_dict
from _paths import SCENES



def worn(shift=None, n=None):
    sc = load_scene(SCENES / "flange_worn.toml")
    if shift is None and n is None:
        return sc
    raw = sc.to_dict()
    if shift is not None:
        raw["geometry"]["lateral_shift"] = shift
    if n is not None:
        raw["grid"] = {"n": n}
    return scene_from_dict(raw, base_dir=SCENES, name="worn")


def test_wheelset_height_is_continuous_up_to_the_flange_contact():
    """0.005 mm apart, the heights differ by less than 0.01 mm (they differed by 11.4 mm), and the
    roll stays at its tread value (0.29 mrad)."""
    geo = worn().geometry
    (r1, z1), (r2, z2) = (wheelset_roll(geo, SCENES, lateral_shift=y) for y in (15.370, 15.375))
    assert abs(z2 - z1) < 0.01 and abs(z1) < 0.1
    assert r1 == pytest.approx(2.88e-4, abs=2e-5) and r2 == pytest.approx(r1, abs=1e-6)


@pytest.mark.slow
def test_sweep_warns_where_the_flange_climbs():
    """Between 15.5 and 15.55 mm the only placement left is the flange tip on the rail: the sweep
    reports the jump (12 mm)."""
    rows = sweep(worn().geometry, [15.45, 15.5, 15.55], SCENES)
    w = jump_warnings(rows)
    assert len(w) == 1 and "15.5 and 15.55" in w[0]
    assert rows[2]["z_ws"] - rows[1]["z_ws"] < -10.0


def test_the_worn_example_stands_on_tread_and_flange_root():
    """The corrected example: two patches (tread about -3 degrees, flange root about -33 degrees),
    the wheelset within 0.1 mm of its nominal height, no placement warning, pmax of a tread contact."""
    import conformal

    r = conformal.solve(worn(n=16))
    assert not any(w.startswith("placement") for w in r.warnings)
    assert abs(r.extra["z_ws"]) < 0.1
    angles = sorted(np.degrees(g["contact_angle"]) for g in r.extra["regions"])
    assert len(angles) == 2 and -40 < angles[0] < -28 and -6 < angles[1] < 0
    assert 300 < r.pmax < 700


def test_placement_warns_at_the_flange_tip():
    """The old example (17 mm): the wheel rides on its flange tip, 13.7 mm above its nominal height."""
    from conformal.cases.wheelrail import place_scene, placement_warnings, state_at

    sc = worn(17.0)
    pl = place_scene(sc)
    st = state_at(pl.pair, pl.top, pl.z_touch + 0.01, pl.roll, sc, grids=False)
    w = " | ".join(placement_warnings(sc, pl, st))
    assert "flange tip" in w and "above its nominal height" in w
    assert -pl.z_touch == pytest.approx(13.74, abs=0.05)


@pytest.mark.parametrize("radius", [10.02, 10.25])
def test_interpolating_spline_does_not_bulge_at_a_groove_kink(radius):
    """A groove of radius R (arc points 0.1 mm apart) meeting flat shoulders at |y| = 9.5 mm (a
    kink of about 70 degrees, as the groove scenes): the interpolating spline overshot the true
    profile by 0.021 mm next to the kink; with the kink's segments subdivided it stays within
    0.003 mm (measured 0.0021 mm at both radii) and still passes through every input point."""
    y0 = 9.5
    th0 = np.arcsin(y0 / radius)
    th = np.linspace(-th0, th0, int(np.ceil(2 * th0 * radius / 0.1)) + 1)
    arc = np.c_[radius * np.sin(th), -(radius - radius * np.cos(th))]
    zk = arc[0, 1]
    flat = np.arange(y0 + 0.2, y0 + 1.01, 0.2)
    pts = np.r_[np.c_[-flat[::-1], np.full(flat.size, zk)], arc, np.c_[flat, np.full(flat.size, zk)]]
    assert kinks(pts).size == 2
    c = fit_curve(pts, 0.0, "groove")
    assert c.smoothing_error < 2e-4
    q = c.point(np.linspace(0.0, c.length, 20001))
    on_flat = np.abs(q[:, 0]) >= y0
    dev = np.where(on_flat, np.abs(q[:, 1] - zk), np.abs(np.hypot(q[:, 0], q[:, 1] + radius) - radius))
    assert dev.max() < 0.003
