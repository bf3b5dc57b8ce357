"""Glue between scene problems and the direct FE contact solve (theory ``"fe_contact"``).

* Quadratic (Hertzian) problems (``[geometry] kind = "quadratic" | "hertz"``): a flat block and a
  crowned wheel whose undeformed distance is A x² + B y² (:func:`solve`, the module's model entry
  point, declared in :mod:`conformal.registry`).
* Wheel-rail scenes: :mod:`conformal.cases.fe_contact` (placement and the curved grid belong to
  the cases layer) meshes the rail and the wheel with :func:`conformal.fe_contact.bodies.wheel_rail_pair`.

``[model]`` keys (all optional; unknown ``fec_*`` keys are rejected):

=====================  =========  ===========================================================
key                    default    meaning
=====================  =========  ===========================================================
``fec_n``              4          elements per (smaller) contact semi-axis on the contact surface
``fec_h``              --         element size on the contact surface in mm (overrides fec_n)
``fec_order``          2          1 (linear) or 2 (quadratic) tetrahedra
``fec_growth``         0.3        increase of the element size per mm away from the contact
``fec_h_max``          0.25       largest element, relative to the body depth
``fec_body_size``      1.0        margin of the bodies beyond the contact patch, in patch sizes
``fec_patch``          1.3        fine patch extent in contact semi-axes (quadratic problems; wheel-rail:
                                  in half extents of the half-space estimate of the contact)
``fec_estimate``       halfspace  wheel-rail: contact size from a half-space solve ("halfspace") or from
                                  the grid ("grid"), see :mod:`conformal.cases.fe_contact`
``fec_far_field``      halfspace  cut faces: "halfspace" (Boussinesq field) or "clamped"
``fec_solver``         auto       "auto" (pypardiso if installed, else scipy splu), "splu", "pardiso"
``fec_body``           disc       wheel-rail: "disc" (profile inside a disc around the patch) or "section"
                                  (ground truth: whole rail section and wheel rim + web, clamped far away;
                                  the far field is then "clamped", no half-space field anywhere) or "block"
                                  (solid blocks around both profiles, clamped far away)
``fec_section_size``   20         "section": rail ends and wheel sector cuts, patch sizes beyond the patch
``fec_section_h_max``  12         "section": largest element (mm)
``fec_slave``          1.6        wheel-rail ("disc" and "section"): contact candidates = the patch
                                  enlarged by this factor
=====================  =========  ===========================================================
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from conformal.errors import InputError
from conformal.fe_contact.bodies import ContactMesh, quadratic_pair
from conformal.fe_contact.solver import (ContactBody, ContactModel, FEContactSettings, FEContactSolution,
                                         recovered_pressure, solve_contact)
from conformal.files import atomic_path
from conformal.result import Result

_MESH_KEYS = {"fec_n": "n", "fec_h": "h", "fec_growth": "growth", "fec_h_max": "h_max",
              "fec_body_size": "body_size", "fec_patch": "patch", "fec_section_size": "section_size",
              "fec_section_h_max": "section_h_max", "fec_slave": "slave"}
_SOLVER_KEYS = {"fec_order": "order", "fec_far_field": "far_field", "fec_solver": "solver"}
_STRING_MESH_KEYS = {"fec_estimate": "estimate", "fec_body": "body"}
KEYS = tuple(sorted(_MESH_KEYS) + sorted(_STRING_MESH_KEYS) + sorted(_SOLVER_KEYS))


def settings_from_options(options: Mapping[str, Any] | None) -> tuple[ContactMesh, FEContactSettings]:
    """Mesh and solver settings from a scene's ``[model]`` keys (see the module docstring).

    >>> mesh, st = settings_from_options({"fec_n": 6, "fec_far_field": "clamped"})
    >>> mesh.n, st.far_field, st.order
    (6, 'clamped', 2)
    """
    opts = {k: v for k, v in dict(options or {}).items() if str(k).startswith("fec_")}
    unknown = sorted(set(opts) - set(KEYS))
    if unknown:
        raise InputError(f"[model] {unknown[0]}: unknown FE contact key (known: {', '.join(KEYS)})")
    mesh_kw, solver_kw = {}, {}
    for k, v in opts.items():
        if k in ("fec_far_field", "fec_solver", "fec_estimate", "fec_body"):
            if not isinstance(v, str):
                raise InputError(f"[model] {k}: must be a string, got {v!r}")
            if k in _STRING_MESH_KEYS:
                mesh_kw[_STRING_MESH_KEYS[k]] = v
            else:
                solver_kw[_SOLVER_KEYS[k]] = v
        elif k in ("fec_n", "fec_order"):
            if isinstance(v, bool) or not isinstance(v, int):
                raise InputError(f"[model] {k}: must be a whole number, got {v!r}")
            (mesh_kw if k == "fec_n" else solver_kw)[_MESH_KEYS.get(k) or _SOLVER_KEYS[k]] = v
        else:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"[model] {k}: must be a number, got {v!r}")
            mesh_kw[_MESH_KEYS[k]] = float(v)
    mesh = ContactMesh(**mesh_kw)
    if mesh.body in ("section", "block"):
        # the ground truth: clamped far away on the real bodies, no half-space field anywhere
        if solver_kw.get("far_field", "clamped") != "clamped":
            raise InputError("[model] fec_far_field: fec_body = \"section\" is clamped far away; "
                             f"\"{solver_kw['far_field']}\" is not available with it")
        solver_kw["far_field"] = "clamped"
    return mesh, FEContactSettings(**solver_kw)


@dataclass(frozen=True, eq=False)
class FEContactRun:
    """A solved FE contact: the bodies and the solution (for VTU output and studies); ``model``
    solves the same meshes again at another approach or load (:class:`ContactModel`)."""

    body1: ContactBody
    body2: ContactBody
    solution: FEContactSolution
    frame: str = "contact"          # "contact" (quadratic problems) | "rail-profile" (wheel-rail)
    model: ContactModel | None = None
    info: dict = field(default_factory=dict)   # wheel-rail: the half-space contact estimate


def extent(sol: FEContactSolution) -> tuple[float, float]:
    """Half extents of the active nodes along x and s (mm)."""
    if not sol.active.any():
        return 0.0, 0.0
    uv = sol.uv[sol.active]
    return 0.5 * float(np.ptp(uv[:, 0])), 0.5 * float(np.ptp(uv[:, 1]))


def common_extra(sol: FEContactSolution, mesh: ContactMesh, st: FEContactSettings) -> dict:
    return {"contact_area": sol.contact_area, "contact_area_bounds": list(sol.contact_area_bounds),
            "pmax_nodal": sol.pmax_nodal, "n_unknowns": sol.n_unknowns,
            "n_contact_nodes": int(sol.active.sum()), "F_load": sol.F_load,
            "fe_contact": {"n": mesh.n, "h": mesh.h, "estimate": mesh.estimate, "order": st.order, "growth": mesh.growth,
                           "body": mesh.body, "section_size": mesh.section_size, "section_h_max": mesh.section_h_max,
                           "h_max": mesh.h_max, "body_size": mesh.body_size, "far_field": st.far_field,
                           **sol.stats}}


def run_quadratic(problem) -> FEContactRun:
    """Mesh and solve a quadratic (Hertzian) :class:`~conformal.problem.ContactProblem`."""
    hz = problem.require_hertz("theory \"fe_contact\"")
    mesh, st = settings_from_options(problem.model.options)
    if mesh.body != "disc":
        raise InputError(f"[model] fec_body: \"{mesh.body}\" needs a wheel-rail scene (a quadratic scene has no real bodies)")
    b1, b2 = quadratic_pair(hz.A, hz.B, (hz.a, hz.b), problem.material, mesh)
    if problem.approach is not None:
        sol = solve_contact(b1, b2, approach=problem.approach, settings=st)
    else:
        sol = solve_contact(b1, b2, normal_force=problem.normal_force, settings=st, approach_guess=hz.approach)
    return FEContactRun(b1, b2, sol)


def solve(problem) -> Result:
    """theory = "fe_contact" for a quadratic problem: frictionless FE contact of a block and a
    crowned wheel with the undeformed distance A x² + B y² (see the module docstring).

    >>> from conformal.scene import scene_from_dict
    >>> from conformal.dispatch import solve_scene
    >>> scene = scene_from_dict({"geometry": {"kind": "quadratic", "A": 0.01, "B": 0.01},
    ...     "load": {"approach": 0.08}, "model": {"theory": "fe_contact", "fec_n": 2}})
    >>> r = solve_scene(scene)                      # doctest: +SKIP
    >>> abs(r.FN / 24296.3 - 1) < 0.03               # doctest: +SKIP
    True
    """
    return result_from_quadratic_run(run_quadratic(problem), problem)


def result_from_quadratic_run(run: FEContactRun, problem) -> Result:
    """The :class:`Result` of :func:`run_quadratic`."""
    sol = run.solution
    a, b = extent(sol)
    mesh, st = settings_from_options(problem.model.options)
    k = problem.kinematics
    return Result(theory="fe_contact", FN=sol.FN, FX=0.0, FY=0.0, MZ=0.0, a=a, b=b, pmax=sol.pmax,
                  approach=sol.approach, xi=k.xi, eta=k.eta, phi=k.phi, converged=True,
                  iterations=sol.iterations, extra=common_extra(sol, mesh, st))


# ----------------------------------------------------------------------------- wheel and rail
def load_direction(grid) -> np.ndarray:
    """The vertical load direction (down, side frame) in the rail-profile frame (x, y, z): the unit
    d with n_I . d = cos(delta_I) for the grid's normals and contact angles."""
    c = float(grid.cant)
    d = np.array([0.0, -math.sin(c), math.cos(c)])
    n = np.asarray(grid.normal, dtype=float)
    if not np.allclose(n @ d[1:], np.cos(grid.delta), atol=1e-6):
        d = np.array([0.0, math.sin(c), math.cos(c)])
        if not np.allclose(n @ d[1:], np.cos(grid.delta), atol=1e-6):
            raise InputError("wheel-rail grid: the load direction does not match the contact angles")
    return d


def pressure_along_profile(sol: FEContactSolution, s: np.ndarray, x: float = 0.0) -> np.ndarray:
    """Nodal pressure interpolated (linearly, Delaunay in (x, s)) at the points (x, s) of body 1's
    surface; 0 outside the slave nodes."""
    from scipy.interpolate import LinearNDInterpolator

    f = LinearNDInterpolator(sol.uv, sol.pressure, fill_value=0.0)
    return np.maximum(f(np.full_like(np.asarray(s, float), x), s), 0.0)


def write_vtu(run: FEContactRun, path) -> list:
    """Write body 1's surface with the nodal and the recovered contact pressure, gap and status
    (``path``) and body 2's
    surface (``<stem>_body2.vtu``) with meshio, in the common frame.  Returns the paths."""
    import meshio
    from pathlib import Path

    path = Path(path)
    sol = run.solution
    m1 = run.body1.mesh
    P1 = run.body1.points
    used = np.unique(m1.free_tris)
    new = -np.ones(len(P1), dtype=np.int64)
    new[used] = np.arange(used.size)
    p = np.zeros(used.size)
    gap = np.full(used.size, np.nan)
    act = np.zeros(used.size)
    p[new[sol.nodes]] = sol.pressure
    pr = np.zeros(used.size)
    pr[new[sol.nodes]] = recovered_pressure(sol)
    gap[new[sol.nodes]] = sol.gap
    act[new[sol.nodes]] = sol.active
    mesh1 = meshio.Mesh(P1[used], [("triangle", new[m1.free_tris])],
                point_data={"pressure": p, "pressure_recovered": pr, "gap": gap, "contact": act})
    with atomic_path(path, keep_suffix=True) as tmp:
        mesh1.write(str(tmp))
    m2 = run.body2.mesh
    P2 = run.body2.points
    used2 = np.unique(m2.free_tris)
    new2 = -np.ones(len(P2), dtype=np.int64)
    new2[used2] = np.arange(used2.size)
    p2 = path.with_name(path.stem + "_body2.vtu")
    with atomic_path(p2, keep_suffix=True) as tmp:
        meshio.Mesh(P2[used2], [("triangle", new2[m2.free_tris])]).write(str(tmp))
    return [path, p2]
