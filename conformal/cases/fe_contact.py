"""A wheel-rail scene solved by direct FE contact (theory ``"fe_contact"``).

The wheelset is placed as for the conformal theory (:func:`~conformal.cases.conformal.curved_problem_from_wheel_rail`:
the same height, the same curved potential-contact grid on the rail); the rail and the wheel are
meshed from the scene's whole profiles around that grid (:func:`conformal.fe_contact.bodies.wheel_rail_pair`)
and pressed together by the scene's approach or vertical wheel load
(:func:`conformal.fe_contact.solver.solve_contact`).  Mesh keys: :mod:`conformal.fe_contact.problems`.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from conformal.cases.conformal import curved_problem_from_wheel_rail
from conformal.fe_contact.bodies import wheel_rail_pair
from conformal.fe_contact.problems import (FEContactRun, common_extra, extent, load_direction,
                                           pressure_along_profile, settings_from_options)
from conformal.fe_contact.solver import prepare_contact
from conformal.influence.fe import rail_body_from_grid
from conformal.result import Result


def run_wheel_rail(scene) -> tuple[FEContactRun, Any]:
    """Mesh the rail and the wheel of a wheel-rail scene around the conformal model's curved grid
    (same wheelset position) and solve at the scene's approach or wheel load.  Returns the run and
    the :class:`~conformal.solvers.conformal.CurvedProblem` it was built from."""
    mesh, st = settings_from_options(scene.model.options)
    problem = curved_problem_from_wheel_rail(scene)
    grid = problem.grid
    b1, b2 = wheel_rail_pair(grid, problem.rail_points, problem.wheel_points, scene.material, mesh)
    model = prepare_contact(b1, b2, direction=load_direction(grid), settings=st)
    if problem.normal_force is not None:
        sol = model.solve(normal_force=problem.normal_force)
    else:
        sol = model.solve(approach=problem.approach)
    return FEContactRun(b1, b2, sol, frame="rail-profile", model=model), problem


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
    return Result(theory="fe_contact", FN=sol.FN, FX=0.0, FY=float(Fy), MZ=0.0, a=a, b=b, pmax=sol.pmax,
                  approach=float(z_ws - problem.info["z_first_touch"]), converged=True, iterations=sol.iterations,
                  extra=extra)


def solve_wheel_rail_fe_contact(scene) -> Result:
    """theory = "fe_contact" for a wheel-rail scene (see the module docstring)."""
    run, problem = run_wheel_rail(scene)
    return result_from_run(run, problem, scene)
