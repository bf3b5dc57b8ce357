"""Wheel-rail cases with the conformal theory: ONE curved strip on the rail over every contact
patch of the wheel, its creepages from the wheelset motion, and its FE or half-space influence
numbers (the body shapes handed to :mod:`conformal.influence.fe`).

The solver itself (Li's conformal contact, Li 2002; seed Eqs. 45-49) is :mod:`conformal.solvers.conformal`; this module builds its
:class:`~conformal.solvers.conformal.CurvedProblem` from a scene.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from conformal.cases.wheelrail import curved_creepages, loaded_state, patch_info, wheelset_motion
from conformal.errors import InputError
from conformal.geometry.patches import curved_grid_for_patch
from conformal.geometry.wheelrail import profile_curves
from conformal.influence.curved import CurvedInfluence
from conformal.influence.fe import settings_from_options, wheel_rail_kernel
from conformal.result import EXTERIOR, Result
from conformal.solvers.conformal import MAX_ELEMENTS, CurvedProblem, column_creepages, solve_curved


def scene_profiles(scene) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Whole rail and wheel profiles (points, 0.1 mm apart) of a wheel-rail scene, so that the FE
    bodies get room beyond the grid's local curves; (None, None) if they cannot be had."""
    try:
        wc, rc = profile_curves(scene.geometry, scene.base_dir)
    except (AttributeError, TypeError):
        return None, None
    return rc.sample(0.1)[1], wc.sample(0.1)[1]


def influence_for_grid(scene, grid, *, cache=None):
    """The FE influence operator (CurvedInfluence) of a wheel-rail scene's curved grid, with the
    scene's [model] fe_* settings, through the cache (``conformal precompute`` fills the same
    entries).  Returns (operator, info)."""
    rail_pts, wheel_pts = scene_profiles(scene)
    geo = scene.geometry
    kernel, info = wheel_rail_kernel(grid, scene.material, settings_from_options(scene.model.options),
                                     cache=cache, rail_points=rail_pts, wheel_points=wheel_pts,
                                     names=(str(geo.rail_profile), str(geo.wheel_profile)))
    return CurvedInfluence.from_kernel(kernel), info


# ----------------------------------------------------------------------------- wheel and rail
def _element_sizes(scene, patches, merged, scale: float) -> tuple[float, float, list[str]]:
    """(dx, ds, warnings) of a strip over several patches: [geometry] element_size (square
    elements, CONTACT's DX = DS), else the extents of the most penetrating patch along x and s
    times [grid] scale over [grid] n elements (the strip gets more elements along s).  At most
    MAX_ELEMENTS ([model] max_mx, max_ms) along each axis: larger strips get coarser elements."""
    es = scene.geometry.element_size
    p, g = patches[0], scene.grid
    if es is not None:
        dx = ds = float(es)
    else:
        dx = (p.x_range[1] - p.x_range[0]) * g.scale / g.n
        ds = max(p.s_range[1] - p.s_range[0], 1e-3) * g.scale / g.n
    warnings = []
    opts = scene.model.options
    for axis, lo_hi, key in (("x", merged.x_range, "max_mx"), ("s", merged.s_range, "max_ms")):
        limit = int(opts.get(key, MAX_ELEMENTS))
        if limit < 2:
            raise InputError(f"[model] {key}: must be >= 2, got {limit}")
        need = (lo_hi[1] - lo_hi[0]) * scale
        size = dx if axis == "x" else ds
        if need / size > limit:
            size = need / limit
            warnings.append(f"the strip over {len(patches)} patch(es) needs more than {limit} elements along "
                            f"{axis}: element size {size:.3g} mm instead (raise [model] {key} for a finer grid)")
            dx, ds = (size, ds) if axis == "x" else (dx, size)
    return dx, ds, warnings


def curved_problem_from_wheel_rail(scene, *, scale: float | None = None) -> CurvedProblem:
    """The conformal problem of a wheel-rail scene: ONE curved grid on the rail that covers every
    contact patch of the wheel (tread and flange at once share the strip, and their elastic
    interaction is included), at the wheelset height of the planar half-space balance.

    h is the signed distance along the local normals at that height; the load is the vertical
    ``[load] wheel_load`` (load direction vertical in the side frame: w = cos delta) or, with
    ``[load] approach``, the height itself (approach 0 from there).  Creepages per column: from the
    wheelset velocities with ``[kinematics] speed`` (the spin follows the contact angle), else from
    the scene's xi, eta, phi at the reference point (:func:`column_creepages`).  ``[model] creepage
    = "reference"`` takes the reference point's creepages with the speed too (the assumption of the
    planar theories; for studies that separate the effect of the geometry from that of the
    kinematics)."""
    pl, st, _ = loaded_state(scene, grids=False)
    load = scene.load
    patches = [pg.patch for pg in st.patches]
    main = patches[0]
    wheel = pl.pair.wheel(st.z)
    g = scene.grid
    scale = scale or g.scale
    size_warnings: list[str] = []
    if len(patches) == 1:   # the grid of conformal.geometry (and of `conformal precompute`)
        merged = main
        grid, h, approach0 = curved_grid_for_patch(wheel, pl.pair.rail, main, element_size=scene.geometry.element_size,
                                                   n=g.n, scale=scale, side=pl.pair.side)
    else:
        merged = replace(main, s_range=(min(p.s_range[0] for p in patches), max(p.s_range[1] for p in patches)),
                         x_range=(min(p.x_range[0] for p in patches), max(p.x_range[1] for p in patches)))
        dx, ds, size_warnings = _element_sizes(scene, patches, merged, scale)
        grid, h, approach0 = curved_grid_for_patch(wheel, pl.pair.rail, merged, sizes=(dx, ds), scale=scale,
                                                   side=pl.pair.side)
    m = pl.pair.mirror
    k, geo = scene.kinematics, scene.geometry
    creep = scene.model.options.get("creepage", "surface")
    if creep not in ("surface", "reference"):
        raise InputError(f"[model] creepage: must be \"surface\" or \"reference\", got {creep!r}")
    motion = wheelset_motion(scene)
    if motion is not None:
        c = curved_creepages(pl.pair, st.z, motion, grid, merged)
        xi_s, eta_s, phi_s = c.xi, m * c.eta, m * c.phi        # back to the side frame of the grid
        if creep == "reference":   # the planar theories' assumption: the reference point's creepages
            xi_s, eta_s, phi_s = column_creepages(grid, *(float(np.interp(grid.s_ref, grid.s, v))
                                                          for v in (xi_s, eta_s, phi_s)))
        kin = replace(k, velocity=float(np.interp(grid.s_ref, grid.s, c.velocity)))
    else:
        xi_s, eta_s, phi_s = column_creepages(grid, k.xi, m * k.eta, m * k.phi)
        kin = k
    info = patch_info(pl.pair, st, st.patches[0], 0)
    info.update(n_geometric_patches=len(patches), z_ws_reference=st.z, z_first_touch=pl.z_first,
                side=pl.pair.side)
    if st.warnings or size_warnings:
        info["warnings"] = list(st.warnings) + size_warnings
    normal = dict(normal_force=load.wheel_load) if load.wheel_load is not None else dict(approach=0.0)
    rail_points, wheel_points = scene_profiles(scene)   # whole profiles for the FE bodies
    profiles = dict(rail_points=rail_points, wheel_points=wheel_points)
    return CurvedProblem(grid=grid, h=h - approach0, material=scene.material, friction=scene.friction,
                         kinematics=kin, model=scene.model, xi_s=np.asarray(xi_s, float),
                         eta_s=np.asarray(eta_s, float), phi_s=np.asarray(phi_s, float), load_angle=0.0,
                         overlap_approach=True,
                         label=f"{scene.name}:{pl.pair.side}", info=info, **normal, **profiles)


def solve_wheel_rail_conformal(scene, *, max_enlarge: int = 2) -> Result:
    """Solve a wheel-rail scene with the conformal theory (see :func:`curved_problem_from_wheel_rail`).

    With a prescribed wheel load the grid is built around the overlap at the planar balance height;
    where the conformal solution needs more room (its contact reaches the border of the grid) the
    grid is rebuilt 1.5 times larger, at most ``max_enlarge`` times."""
    scale = scene.grid.scale
    for attempt in range(max_enlarge + 1):
        problem = curved_problem_from_wheel_rail(scene, scale=scale)
        result = solve_curved(problem)
        contact = result.field.status != EXTERIOR
        if not (contact[0].any() or contact[-1].any() or contact[:, 0].any() or contact[:, -1].any()):
            break
        scale *= 1.5
    z_ws = problem.info["z_ws_reference"] + (result.extra["approach_along_load"]
                                             if problem.normal_force is not None else 0.0)
    # ``approach`` means what [load] approach means: the wheelset's lowering below the height where
    # its first wheel touches; the largest overlap along the local normals is ``overlap_max``
    return replace(result, approach=float(z_ws - problem.info["z_first_touch"]),
                   extra=dict(result.extra, z_ws=z_ws, grid_scale=scale, enlargements=attempt,
                              wheel_load=scene.load.wheel_load, overlap_max=result.approach))
