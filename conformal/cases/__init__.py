"""Cases: orchestration above the solvers.

A wheel-rail case (:mod:`conformal.cases.wheelrail`, :mod:`conformal.cases.conformal`) places the
wheelset, balances the vertical load with contact solves, builds the planar or curved grids,
derives the creepages from the wheelset motion and assembles the patches into one result, from
the geometry, influence and solver layers below.  :mod:`conformal.cases.precompute` plans the FE
influence numbers a sweep of wheel-rail positions will need.
"""
from conformal.registry import CURVED_STRIP, FE_BODIES, MODELS
from conformal.cases.wheelrail import problems_from_wheel_rail
from conformal.cases.wheelrail import solve_wheel_rail as solve_wheel_rail_planar

__all__ = ["problems_from_wheel_rail", "solve_wheel_rail", "solve_wheel_rail_conformal", "solve_wheel_rail_planar"]


def __getattr__(name: str):
    # the curved-strip case (and what it imports) loads when first used: planar wheel-rail solves do
    # not need it
    if name == "solve_wheel_rail_conformal":
        from conformal.cases.conformal import solve_wheel_rail_conformal

        return solve_wheel_rail_conformal
    raise AttributeError(f"module 'conformal.cases' has no attribute {name!r}")


def solve_wheel_rail(scene, *, warm=None):
    """Solve a wheel-rail scene with its model: the conformal theory on one curved strip per wheel
    (:func:`~conformal.cases.conformal.solve_wheel_rail_conformal`), every other model per
    contact patch on its tangent plane (:func:`~conformal.cases.wheelrail.solve_wheel_rail`).

    Parameters
    ----------
    scene : conformal.scene.Scene
        A scene with ``[geometry] kind = "wheel_rail"``.
    warm : conformal.cases.wheelrail.WarmStart, optional
        Where a neighbouring solve (a sweep's previous position) balanced the wheel load: the
        vertical balance starts from there (planar theories and the conformal strip's placement).

    Returns
    -------
    Result
        Totals in the contact frames (FN, FX, FY), the track-frame forces on the rail
        ``extra["FX_track"]``, ``["FY_track"]``, ``["FZ_track"]``, and ``approach``: the wheelset's
        lowering below its first touch (the meaning of ``[load] approach``).

    Examples
    --------
    >>> from conformal.cli import demo_scene_path
    >>> from conformal.scene import load_scene
    >>> s = load_scene(demo_scene_path()).with_(model__theory="hertz")
    >>> r = solve_wheel_rail(s)
    >>> round(r.extra["FZ_track"]), r.theory           # the 10 kN wheel load, balanced vertically
    (10000, 'hertz')
    """
    if MODELS.accepts(scene.model.theory, FE_BODIES):   # direct FE contact of the meshed wheel and rail
        from conformal.cases.fe_contact import solve_wheel_rail_fe_contact
        return solve_wheel_rail_fe_contact(scene)
    if MODELS.accepts(scene.model.theory, CURVED_STRIP):
        from conformal.cases.conformal import solve_wheel_rail_conformal

        return solve_wheel_rail_conformal(scene, warm=warm)
    return solve_wheel_rail_planar(scene, warm=warm)
