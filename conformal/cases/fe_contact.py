"""A wheel-rail scene solved by direct FE contact (theory ``"fe_contact"``).

The wheelset is placed as for the conformal theory (:func:`~conformal.cases.conformal.curved_problem_from_wheel_rail`:
the same height, the same curved potential-contact grid on the rail); the rail and the wheel are
meshed from the scene's whole profiles around that grid (:func:`conformal.fe_contact.bodies.wheel_rail_pair`)
and pressed together by the scene's approach or vertical wheel load
(:func:`conformal.fe_contact.solver.solve_contact`).  Mesh keys: :mod:`conformal.fe_contact.problems`.

Mesh size (``[model] fec_estimate = "halfspace"``, the default): the contact is first solved on the
same curved grid with half-space influence numbers, frictionless (:func:`contact_estimate`, a
second or less); its contact area gives the smaller contact semi-axis a (the element size on the
contact is h = a / ``fec_n``, unless ``fec_h`` is given) and the finely meshed patch, the box
around it enlarged by ``fec_patch`` (its half extents times fec_patch), clipped to the grid.  A
narrow contact (the deep groove: 0.75 mm wide, 12 mm long) so gets elements that resolve its
width, a wide one no finer elements than it needs.  ``fec_estimate = "grid"``: the whole grid is
the patch and a = half its smaller extent / 1.1.

Bodies (``[model] fec_body``): "disc" (default; quasi-quarter spaces cut out of the profiles,
half-space field or clamped on the cut faces), "section" (the ground truth on real bodies: the
60E1 rail section and the wheel's rim and web, clamped far away) or "block" (solid blocks around
both profiles, clamped far away): :func:`conformal.fe_contact.bodies.section_pair`.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from conformal.cases.conformal import curved_problem_from_wheel_rail
from conformal.errors import NoContactError
from conformal.fe_contact.bodies import slave_box, slave_region, wheel_rail_pair
from conformal.fe_contact.problems import (FEContactRun, common_extra, extent, load_direction,
                                           pressure_along_profile, settings_from_options)
from conformal.fe_contact.solver import prepare_contact
from conformal.influence.fe import rail_body_from_grid
from conformal.registry import FE_BODIES, MODELS
from conformal.result import Result


def contact_estimate(problem) -> dict:
    """The contact of a :class:`~conformal.solvers.conformal.CurvedProblem` with half-space
    influence numbers, frictionless, at the problem's load or approach: the half extents of its
    elements in contact (``x_half`` about x = 0, ``s_lo``/``s_hi`` in the grid's arc length,
    ``semi_axis`` = the smaller of x_half and (s_hi - s_lo) / 2) and its FN.  Raises
    NoContactError where nothing is in contact."""
    from dataclasses import replace

    from conformal.result import EXTERIOR
    from conformal.solvers.conformal import solve_curved

    zero = np.zeros(problem.grid.ms)
    model = replace(problem.model, theory="conformal", influence="halfspace",
                    options={k: v for k, v in problem.model.options.items() if not str(k).startswith("fec_")})
    r = solve_curved(replace(problem, model=model, xi_s=zero, eta_s=zero, phi_s=zero))
    contact = np.asarray(r.field.status) != EXTERIOR
    if not contact.any():
        raise NoContactError("fe_contact: the half-space estimate finds no contact")
    g = problem.grid
    xe = g.xl + g.dx * np.arange(g.mx + 1)
    se = np.asarray(g.s_edges, dtype=float)
    ix = np.where(contact.any(axis=1))[0]
    js = np.where(contact.any(axis=0))[0]
    x_half = float(max(abs(xe[ix[0]]), abs(xe[ix[-1] + 1])))
    s_lo, s_hi = float(se[js[0]]), float(se[js[-1] + 1])
    return {"x_half": x_half, "s_lo": s_lo, "s_hi": s_hi, "semi_axis": min(x_half, 0.5 * (s_hi - s_lo)),
            "FN": float(r.FN)}


def run_wheel_rail(scene) -> tuple[FEContactRun, Any]:
    """Mesh the rail and the wheel of a wheel-rail scene around the conformal model's curved grid
    (same wheelset position) and solve at the scene's approach or wheel load.  Returns the run and
    the :class:`~conformal.solvers.conformal.CurvedProblem` it was built from.  The mesh size and
    the fine patch follow the half-space estimate of the contact (see the module docstring)."""
    mesh, st = settings_from_options(scene.model.options)
    problem = curved_problem_from_wheel_rail(scene)
    grid = problem.grid
    kw: dict = {}
    est: dict = {}
    if mesh.estimate == "halfspace":
        est = contact_estimate(problem)
        c = 0.5 * (est["s_lo"] + est["s_hi"])
        half = 0.5 * (est["s_hi"] - est["s_lo"])
        kw = {"semi_axis": est["semi_axis"],
              "box": (mesh.patch * est["x_half"], c - mesh.patch * half, c + mesh.patch * half)}
    b1, b2 = wheel_rail_pair(grid, problem.rail_points, problem.wheel_points, scene.material, mesh, **kw)
    # a disc body's contact candidates: its patch enlarged by fec_slave (bodies.slave_region; the
    # section bodies' free surface is that box already)
    x_half = max(abs(grid.xl), abs(grid.xl + grid.mx * grid.dx))
    if "box" in kw:
        x_half = min(x_half, kw["box"][0])
    region = slave_region(b1.mesh.patch, mesh.slave, x_half) if mesh.body == "disc" else None
    model = prepare_contact(b1, b2, direction=load_direction(grid), settings=st, region=region)
    if problem.normal_force is not None:
        sol = model.solve(normal_force=problem.normal_force)
    else:
        sol = model.solve(approach=problem.approach)
    info = {"estimate": est, "h_contact": float(b1.mesh.patch.dx),
            "bodies": {b.mesh.body.kind: _body_report(b.mesh) for b in (b1, b2)}}
    if region is not None:
        info["slave_box"] = [float(v) for v in slave_box(b1.mesh.patch, mesh.slave, x_half)]
    return FEContactRun(b1, b2, sol, frame="rail-profile", model=model, info=info), problem


def _body_report(m) -> dict:
    """What a meshed body really is: its disc radius and margin (mm), the closure of its profile's
    ends, its nodes and tetrahedra (:func:`conformal.meshing.gmsh_body.mesh_body`'s stats)."""
    keys = ("disc_radius_mm", "margin_mm", "margin_requested_mm", "closure_lo", "closure_hi", "extension_lo_mm",
            "extension_hi_mm", "margin_limited_by", "nodes", "tets")
    return {k: m.stats[k] for k in keys if k in m.stats}


def edge_warning(run: FEContactRun) -> str:
    """A warning where the contact reaches the edge of the contact candidates (``[model]
    fec_slave``): the contact may be larger than the candidates allow."""
    box = run.info.get("slave_box")
    sol = run.solution
    if not box or not sol.active.any():
        return ""
    uv = sol.uv[sol.active]
    h = float(run.info.get("h_contact", 0.0))
    xs, s_lo, s_hi = box
    if np.abs(uv[:, 0]).max() > xs - 1.5 * h or uv[:, 1].min() < s_lo + 1.5 * h or uv[:, 1].max() > s_hi - 1.5 * h:
        return ("fe_contact: the contact reaches the edge of the contact candidates (the patch enlarged by "
                "[model] fec_slave); increase fec_slave or fec_patch")
    return ""


def result_from_run(run: FEContactRun, problem, scene) -> Result:
    """The :class:`Result` of a wheel-rail FE contact run: FN the total normal force on the rail;
    FY (= ``FY_side``) and ``FZ_side`` its lateral and vertical parts in the side frame; FX = MZ = 0
    (frictionless); approach: the wheelset height from first touch (as the conformal theory reports
    it; ``overlap_approach``: the largest rigid overlap along the local normals); ``profile_s``, ``profile_p``: the pressure along the grid's arc length at
    x = 0."""
    sol = run.solution
    mesh, st = settings_from_options(scene.model.options)
    grid = problem.grid
    F = sol.force_vector                                       # on the rail, rail-profile frame
    c = float(grid.cant)
    Rm = np.array([[math.cos(c), math.sin(c)], [-math.sin(c), math.cos(c)]])
    Fy, Fz = Rm @ F[1:]
    a, b = extent(sol)
    s = np.linspace(grid.s_edges[0], grid.s_edges[-1], 201)
    _, rpatch = rail_body_from_grid(grid, problem.rail_points)
    s_fe = np.interp(s, grid.s_edges, rpatch.edges)           # grid arc length -> FE profile arc length
    extra = common_extra(sol, mesh, st)
    extra.update({"FY_side": float(Fy), "FZ_side": float(Fz), "approach_along_load": sol.approach,
                  "profile_s": s, "profile_p": pressure_along_profile(sol, s_fe),
                  "profile_s_ref": float(grid.s_ref), "z_ws_reference": problem.info.get("z_ws_reference")})
    z_ws = problem.info["z_ws_reference"] + sol.approach          # the wheelset moves along d (vertical)
    extra.update({"z_ws": z_ws, "overlap_approach": sol.overlap_approach})
    extra["fe_contact"].update(run.info)
    if edge_warning(run):
        extra["warnings"] = list(extra.get("warnings", [])) + [edge_warning(run)]
    return Result(theory="fe_contact", FN=sol.FN, FX=0.0, FY=float(Fy), MZ=0.0, a=a, b=b, pmax=sol.pmax,
                  approach=float(z_ws - problem.info["z_first_touch"]), converged=True, iterations=sol.iterations,
                  extra=extra)


def solve_wheel_rail_fe_contact(scene) -> Result:
    """theory = "fe_contact" for a wheel-rail scene (see the module docstring)."""
    run, problem = run_wheel_rail(scene)
    return result_from_run(run, problem, scene)


def solve_scene_with_run(scene) -> tuple[Result, FEContactRun]:
    """theory = "fe_contact" for any scene (wheel-rail or quadratic), returning the run as well
    (the meshed bodies, for :func:`conformal.fe_contact.problems.write_vtu`: ``conformal solve
    --vtu``).  The result is :func:`conformal.dispatch.solve_scene`'s, with ``wall_s``."""
    import time
    from dataclasses import replace

    from conformal._threads import single_threaded_blas
    from conformal.errors import InputError
    from conformal.fe_contact.problems import result_from_quadratic_run, run_quadratic
    from conformal.problem import problems_from_scene
    from conformal.scene import scene_warnings

    if not MODELS.accepts(scene.model.theory, FE_BODIES):
        raise InputError(f"[model] theory: needs {MODELS.quoted(FE_BODIES)}, got {scene.model.theory!r}")
    t0 = time.perf_counter()
    with single_threaded_blas():
        if scene.geometry.kind == "wheel_rail":
            run, problem = run_wheel_rail(scene)
            result = result_from_run(run, problem, scene)
        else:
            problems = problems_from_scene(scene)
            if len(problems) != 1:
                raise InputError(f"theory \"fe_contact\": needs one contact problem, the scene gives {len(problems)}")
            run = run_quadratic(problems[0])
            result = result_from_quadratic_run(run, problems[0])
    warnings = scene_warnings(scene) + result.warnings
    if warnings:
        result = replace(result, extra=dict(result.extra, warnings=list(dict.fromkeys(warnings))))
    return replace(result, wall_s=time.perf_counter() - t0), run
