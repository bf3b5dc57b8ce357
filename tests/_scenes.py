"""Scenes several test files build: one builder each, the per-file numbers stay in the tests.

``from _scenes import mbench_scene`` in any test module (tests/ is on ``sys.path``).
"""
from __future__ import annotations

from _paths import SCENES

#: the Manchester contact benchmark A-2.2 pair (S1002 on UIC60 1:40, CONTACT examples/mbench_a22)
MBENCH = SCENES / "mbench_right_y5.toml"


def mbench_scene(y: float = 5.0, side: str = "right", *, theory: str = "exact", element_size: float = 0.4,
                 **geometry):
    """The Manchester A-2.2 pair at lateral shift ``y`` (mm) with the benchmark's yaw 0.0024 y (rad);
    further ``[geometry]`` keys (``roll=...``) as keywords."""
    from conformal.scene import load_scene

    changes = dict(lateral_shift=y, yaw=0.0024 * y, side=side, element_size=element_size, **geometry)
    return load_scene(MBENCH).with_(model__theory=theory, **{f"geometry__{k}": v for k, v in changes.items()})


def mbench_case_scene(inputs: dict, side: str = "right", *, theory: str = "exact", element_size: float = 0.4):
    """The Manchester A-2.2 pair at one of CONTACT's cases: ``inputs`` is the case's ``"inputs"`` in
    tests/reference/contact_cases.json (``mbench_a22``: lateral shift, yaw, roll, pitch velocity;
    studies/manchester_a22.scene_for)."""
    from conformal.scene import load_scene

    return load_scene(MBENCH).with_(
        geometry__side=side, geometry__lateral_shift=inputs["Y_WS_mm"], geometry__yaw=inputs["YAW_WS_rad"],
        geometry__roll=inputs["ROLL_WS_rad"], geometry__element_size=element_size,
        kinematics__pitch_velocity=inputs["VPITCH_rad_per_s"], model__theory=theory)


def mbench_case_pairs(cases, neighbour_dy: float | None = None):
    """(name, pair) of both wheels at each of CONTACT's Manchester A-2.2 ``cases`` (their
    ``"inputs"``, :func:`mbench_case_scene`), named "right 5" / "left 5"; with ``neighbour_dy``
    also the right wheel at the shift less it ("right 4.9": the lift check's neighbour)."""
    from conformal.geometry.wheelrail import build_pair

    for c in cases:
        sc = mbench_case_scene(c["inputs"])
        geo, y = sc.geometry, c["inputs"]["Y_WS_mm"]
        for side in ("right", "left"):
            yield f"{side} {y:g}", build_pair(geo, sc.base_dir, side=side, roll=geo.roll)
        if neighbour_dy is not None:
            yield (f"right {y - neighbour_dy:g}",
                   build_pair(geo, sc.base_dir, side="right", roll=geo.roll, lateral_shift=y - neighbour_dy))


def hertz_scene(a: float, b: float, normal_force: float, *, theory: str, material: dict | None = None,
                mu: float = 0.3, kinematics: dict | None = None, grid: dict | None = None, **model):
    """A Hertzian contact given by its ellipse (``[geometry] kind = "hertz"``, semi-axes ``a``, ``b``
    in mm) under ``normal_force`` (N); ``material`` defaults to steel (G = 82000 N/mm², nu = 0.28);
    model keys other than ``theory`` as keywords."""
    from conformal.scene import scene_from_dict

    data = {"material": dict(material or {"G": 82000.0, "nu": 0.28}), "friction": {"mu": mu},
            "geometry": {"kind": "hertz", "a": a, "b": b}, "load": {"normal_force": normal_force},
            "kinematics": dict(kinematics or {}), "model": {"theory": theory, **model}}
    if grid:
        data["grid"] = dict(grid)
    return scene_from_dict(data)


def hertz_problem(a: float, b: float, normal_force: float, **kw):
    """The one contact problem of :func:`hertz_scene` (same arguments)."""
    from conformal.problem import problems_from_scene

    return problems_from_scene(hertz_scene(a, b, normal_force, **kw))[0]


#: a small wheel-rail scene (S1002/UIC60, 6 x 6 strip, small FE bodies) for precompute
SWEEP_SCENE = """\
name = "sweep"
[material]
G = 82000.0
nu = 0.28
[friction]
mu = 0.3
[geometry]
kind = "wheel_rail"
wheel_profile = "S1002"
rail_profile = "UIC60"
lateral_shift = 0.0
[load]
wheel_load = 50000.0
[grid]
n = 6
[model]
theory = "conformal"
fe_body_size = 0.7
"""


def tight_general_balance(scene):
    """The general vertical balance of a wheel-rail scene run cold with the force and height
    tolerances 1e-8 W and 1e-7 mm, its geometry searched at the balanced height (the reference the
    sweep's one-patch passes are checked against): (combined result, wheelset height z)."""
    import conformal.cases.wheelrail as wr

    pl = wr.place_scene(scene)
    tight = {"BALANCE_TOL": 1e-8, "BALANCE_ZTOL": 1e-7}
    old = {k: getattr(wr, k) for k in tight}
    try:
        for k, v in tight.items():
            setattr(wr, k, v)
        _, z, res, probs, _, _, _ = wr._general_passes(scene, pl, None, None, [], [], 40)
    finally:
        for k, v in old.items():
            setattr(wr, k, v)
    return wr.combine_patches(res, probs, scene.model.theory, {}, pl.pair), z
