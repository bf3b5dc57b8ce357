"""The schema of a result: the fields of the JSON summary (``conformal solve``, :meth:`Result.summary
<conformal.result.Result.summary>`) and the keys of ``Result.extra``, with their units.

Units: mm, N, N/mm², rad (angles named ``*_deg`` in degrees), s; creepages dimensionless, spin in
rad/mm.  Forces act on body 1 (the rail) in the contact frame unless the name says ``_track``
(the track frame: x along the track, y lateral, z vertical) or ``_side``.  The JSON's field names
are a public interface: add, never rename.  ``where`` names the models or scenes that write a key
(``wheel-rail``: the wheel-rail cases, any theory).  tests/unit/test_schema.py checks that the results of
every theory carry only documented keys.

>>> SUMMARY["FN"].unit, EXTRA["FZ_track"].unit, EXTRA["elastic_energy"].unit
('N', 'N', 'J')
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Field:
    """One JSON field or ``Result.extra`` key: its unit ("" for none), meaning and writers."""

    unit: str
    doc: str
    where: str = "every model"


#: the fields of every JSON summary (Result's own attributes; ``patches`` lists the parts' summaries)
SUMMARY = {
    "theory": Field("", "the model that solved it ([model] theory)"),
    "FN": Field("N", "normal force on body 1 (per mm of line length for line contact)"),
    "FX": Field("N", "longitudinal (rolling direction) tangential force on body 1, contact frame"),
    "FY": Field("N", "lateral tangential force in the contact plane on body 1"),
    "FS": Field("N", "the same as FY (the lateral force along the profile, CONTACT's FS)"),
    "MZ": Field("N mm", "spin moment about the contact normal"),
    "a": Field("mm", "semi-axis along x (rolling): Hertz ellipse or extent of the computed patch"),
    "b": Field("mm", "semi-axis along y (null for line contact)"),
    "pmax": Field("N/mm²", "largest contact pressure"),
    "approach": Field("mm", "approach of the bodies (wheel-rail: the wheelset's lowering below first touch)"),
    "xi": Field("", "longitudinal creepage used (the solved one where a force was prescribed)"),
    "eta": Field("", "lateral creepage used"),
    "phi": Field("rad/mm", "spin creepage used"),
    "n_contact": Field("", "grid elements in contact (null without a grid)"),
    "n_slip": Field("", "grid elements in slip"),
    "converged": Field("", "true when the iterations met [model] tol (false: the numbers are not a solution)"),
    "iterations": Field("", "iterations of the solver (null where not iterative)"),
    "residual": Field("", "relative change of the tractions at the last iteration"),
    "wall_s": Field("s", "wall time of the solve"),
    "patches": Field("", "the summaries of the contact patches or strips (same fields)", "wheel-rail, several patches"),
    "warnings": Field("", "physically questionable inputs or results, one sentence each"),
}

_G = "exact, conformal"
_WR = "wheel-rail"
_CF = "conformal"

#: the keys of ``Result.extra`` (also fields of the JSON summary)
EXTRA = {
    # Hertz and the planar theories
    "A": Field("1/mm", "curvature of the undeformed distance along x (h = A x² + B y²)", "hertz"),
    "B": Field("1/mm", "curvature along y", "hertz"),
    "area": Field("mm²", "contact area pi a b", "hertz"),
    "hertz": Field("", "the Hertz solution of the quadratic geometry: a, b (mm), pmax (N/mm²), approach (mm), "
                   "FN (N)", _G),
    "C11": Field("", "Kalker's creep coefficient C11 at (a/b, nu)", "linear"),
    "C22": Field("", "Kalker's creep coefficient C22", "linear"),
    "C23": Field("", "Kalker's creep coefficient C23", "linear"),
    "C33": Field("", "Kalker's creep coefficient C33 (null when not needed)", "linear"),
    "coefficients": Field("", "source of the creep coefficients", "linear"),
    "note": Field("", "a remark on the model's validity", "linear"),
    "F_over_muFN": Field("", "total creep force over mu FN", "linear, empirical, johnson_vermeulen, table"),
    "law": Field("", "the creep-force law: kalker | johnson_vermeulen", "empirical, johnson_vermeulen"),
    "creep_coefficients": Field("", "the normalisation of the creepages: kalker | elliptic",
                                "empirical, johnson_vermeulen"),
    "tau": Field("", "normalised creepage sqrt(xi'² + eta'²) (seed Eqs. 18-20)", "empirical, johnson_vermeulen"),
    "phi_coefficient": Field("", "Vermeulen-Johnson's phi of the ellipse (seed Eq. 18)", "empirical, johnson_vermeulen"),
    "psi_coefficient": Field("", "Vermeulen-Johnson's psi of the ellipse (seed Eq. 18)", "empirical, johnson_vermeulen"),
    "note_MZ": Field("", "the spin moment is not part of the law", "empirical, johnson_vermeulen"),
    "note_spin": Field("", "spin is not part of the law", "empirical, johnson_vermeulen"),
    "table": Field("", "the creep-force table file", "table"),
    "table_hash": Field("", "first 16 hex digits of the table's content hash", "table"),
    "L1": Field("mm³/N", "FASTSIM flexibility for xi (layer included)", "fastsim"),
    "L2": Field("mm³/N", "FASTSIM flexibility for eta", "fastsim"),
    "L3": Field("mm³/N", "FASTSIM flexibility for phi", "fastsim"),
    "flexibilities": Field("", "where L1, L2, L3 came from (Kalker's coefficients or [model] flexibilities)",
                           "fastsim"),
    "layer_flexibility": Field("mm/(N/mm²)", "contamination layer flexibility (seed Eqs. 34-36)", "fastsim"),
    "bound": Field("", "traction bound: parabolic | elliptic", "fastsim"),
    "discretisation": Field("", "strip sampling: midpoint | contact", "fastsim"),
    "FN_grid": Field("N", "normal force of the sampled pressure on the strips", "fastsim"),
    "FX_over_muFN": Field("", "FX over mu FN", "fastsim"),
    "FY_over_muFN": Field("", "FY over mu FN", "fastsim"),
    # the grid solvers
    "grid": Field("", "the potential contact grid: mx, my (or ms), dx, dy (or ds) in mm", "exact, conformal, fastsim"),
    "n_potential": Field("", "elements of the potential contact grid", _G),
    "n_adhesion": Field("", "elements in adhesion", _G),
    "normal_iterations": Field("", "iterations of the normal problem (seed Eqs. 45-46)", _G),
    "normal_residual": Field("", "relative change of the pressure at the last normal iteration", _G),
    "tangential_iterations": Field("", "iterations of the tangential problem (seed Eqs. 47-49)", _G),
    "tangential_residual": Field("", "relative change of the tangential tractions at the last iteration", _G),
    "gap_residual": Field("", "largest gap violation relative to the approach", _G),
    "elastic_energy": Field("J", "elastic energy of the tractions, (1/2) sum p . u dA / 1000", _G),
    "frictional_power": Field("W", "frictional power V sum p_t . s dA / 1000 (steady rolling)", _G),
    "FX_rel": Field("", "FX over mu FN", _G),
    "FY_rel": Field("", "FY over mu FN", _G),
    "FN_over_G": Field("mm²", "FN over the combined shear modulus", "exact"),
    "patch_FN": Field("N", "normal force per separate contact region of the grid", "exact"),
    "outer": Field("", "the normal-tangential (Panagiotopoulos) iterations: changes per outer pass", _G),
    "outer_iterations": Field("", "outer (normal-tangential) passes", _G),
    "line_contact": Field("", "true: plane strain on the half-plane, forces per mm of line length",
                          "exact, [geometry] B = 0"),
    "reference_length": Field("mm", "datum depth of the half-plane displacement", "exact, [geometry] B = 0"),
    "per_unit_length": Field("", "the units of the forces of a line contact", "exact, [geometry] B = 0"),
    "history": Field("", "one summary per applied [[history]] step", "exact, [[history]]"),
    "history_rolling": Field("", "the rolling kind of the step: shift | transient | steady", "exact, [[history]]"),
    "n_reversed": Field("", "elements whose slip reversed against the previous traction", "exact, [[history]]"),
    "shift_total": Field("mm", "accumulated rigid shift (x, y) of the shift and transient steps",
                         "exact, [[history]]"),
    # wheel-rail cases (any theory)
    "FX_track": Field("N", "force on the rail along the track", _WR),
    "FY_track": Field("N", "lateral force on the rail (track frame)", _WR),
    "FZ_track": Field("N", "vertical force on the rail (track frame; the wheel load when balanced)", _WR),
    "n_patches": Field("", "contact patches of the wheel", _WR),
    "contact_angle": Field("rad", "contact angle of the (most loaded) patch, 0 = vertical", _WR),
    "y_rail": Field("mm", "lateral position of the contact point on the rail profile", _WR),
    "z_rail": Field("mm", "vertical position of the contact point on the rail profile", _WR),
    "s_rail": Field("mm", "arc length of the contact point along the rail profile", _WR),
    "y_wheel": Field("mm", "lateral position of the contact point on the wheel profile", _WR),
    "z_wheel": Field("mm", "height of the contact point on the wheel profile", _WR),
    "x_track": Field("mm", "position of the patch along the track", _WR),
    "y_track": Field("mm", "lateral position of the patch (track frame)", _WR),
    "z_track": Field("mm", "vertical position of the patch (track frame)", _WR),
    "rolling_radius": Field("mm", "wheel radius at the contact point", _WR),
    "penetration": Field("mm", "overlap of the undeformed profiles at the (most loaded) patch", _WR),
    "patch": Field("", "index of the patch", _WR),
    "n_lobes": Field("", "separate overlap regions merged into the patch", _WR),
    "curvature_A": Field("1/mm", "relative curvature along x at the patch", _WR),
    "curvature_B": Field("1/mm", "relative curvature across at the patch", _WR),
    "hertz_angle": Field("rad", "the contact angle the Hertz patch is solved at", _WR),
    "side": Field("", "right | left wheel", _WR),
    "roll": Field("rad", "wheelset roll", _WR),
    "z_ws": Field("mm", "wheelset height (positive down) at the solution", _WR),
    "wheel_load": Field("N", "the prescribed wheel load", _WR),
    "balance": Field("", "the vertical balance: iterations, solves, lowering", _WR),
    "balance_iterations": Field("", "passes of the vertical balance", _WR),
    "smoothing_error_wheel": Field("mm", "largest deviation of the smoothed wheel profile from its points", _WR),
    "smoothing_error_rail": Field("mm", "largest deviation of the smoothed rail profile from its points", _WR),
    "contact_angle_spread_deg": Field("deg", "variation of the contact angle over the patch", _WR),
    "xi_patch": Field("", "longitudinal creepage of the patch", _WR),
    "eta_patch": Field("", "lateral creepage of the patch", _WR),
    "phi_patch": Field("rad/mm", "spin creepage of the patch", _WR),
    "hertz_a": Field("mm", "Hertz semi-axis a of the patch", _WR),
    "hertz_b": Field("mm", "Hertz semi-axis b of the patch", _WR),
    "hertz_pmax": Field("N/mm²", "Hertz peak pressure of the patch", _WR),
    "rolling_velocity": Field("mm/s", "rolling velocity at the patch", _WR),
    "label": Field("", "name of the problem (scene:side:patch)", _CF),
    # the conformal strip
    "MZ_3d": Field("N mm", "spin moment about the reference normal in 3-D", _CF),
    "contact_angle_min": Field("rad", "smallest contact angle in contact", _CF),
    "contact_angle_max": Field("rad", "largest contact angle in contact", _CF),
    "contact_area": Field("mm²", "area in contact (on the curved surface)", _CF),
    "influence": Field("", "the influence numbers used: halfspace | halfspace_planar | fe", _CF),
    "influence_s": Field("s", "time to build the influence numbers", _CF),
    "solve_s": Field("s", "time of the contact iterations", _CF),
    "regions": Field("", "the contact regions of the strip (per region: FN, extents, contact angles)", _CF),
    "load_angle": Field("rad", "direction the wheel is pressed along", _CF),
    "approach_along_load": Field("mm", "approach along the load direction", "conformal, fe_contact"),
    "approach_reference": Field("mm", "the height of the reference (first touch) below which approach counts", _CF),
    "overlap_max": Field("mm", "largest overlap of the undeformed strip", _CF),
    "z_first_touch": Field("mm", "wheelset height at first touch", _CF),
    "z_ws_reference": Field("mm", "wheelset height the strip was built at", "conformal, fe_contact"),
    "n_geometric_patches": Field("", "overlap regions the strip covers", _CF),
    "grid_scale": Field("", "[grid] scale used", _CF),
    "enlargements": Field("", "times the strip was enlarged (contact at its border)", _CF),
    "strips": Field("", "coupled | separate (one strip per patch)", _CF),
    "n_strips": Field("", "strips solved ([grid] strips = separate)", _CF),
    "separate_strips": Field("", "per strip: FN, FX, FS, FY_track, FZ_track (N), area (mm²), pmax, contact "
                             "angles", _CF),
    "coupled_strip": Field("", "the coupled strip's totals beside the separate ones", _CF),
    "pitch_velocity_solved": Field("rad/s", "pitch velocity of a prescribed force (fx_rel)", _CF),
    "pitch_creepage_solved": Field("", "the reference column's creepage at that pitch", _CF),
    "pitch_creepage_free": Field("", "creepage of free rolling (fx_rel = 0)", _CF),
    "reference_rolling_radius": Field("mm", "rolling radius of the reference column", _CF),
    "pitch_solves": Field("", "solves of the pitch root search", _CF),
    # direct FE contact
    "fe_contact": Field("", "FE contact details: mesh sizes, unknowns, contact nodes, far field", "fe_contact"),
    "FY_side": Field("N", "lateral force on the rail, side frame", "fe_contact"),
    "FZ_side": Field("N", "vertical force on the rail, side frame", "fe_contact"),
    "overlap_approach": Field("", "the approach counts from overlapping profiles", "fe_contact"),
    "profile_s": Field("mm", "arc lengths of the pressure profile along the rail", "fe_contact"),
    "profile_p": Field("N/mm²", "pressure along the rail profile", "fe_contact"),
    "profile_s_ref": Field("mm", "arc length of the reference point", "fe_contact"),
}


def markdown() -> str:
    """The schema as markdown tables (for the documentation site).

    >>> "| `FZ_track` | N |" in markdown()
    True
    """
    out = ["# Result fields", "", "## Every result", "", "| field | unit | meaning |", "|---|---|---|"]
    out += [f"| `{k}` | {f.unit} | {f.doc} |" for k, f in SUMMARY.items()]
    out += ["", "## Model-specific fields (`Result.extra`)", "", "| field | unit | meaning | written by |",
            "|---|---|---|---|"]
    out += [f"| `{k}` | {f.unit} | {f.doc.replace('|', '/')} | {f.where} |" for k, f in EXTRA.items()]
    return "\n".join(out) + "\n"
