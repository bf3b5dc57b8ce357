"""Rolling in -x (``[kinematics] direction = -1``): the problem mirrored x -> -x, solved by any
planar model as rolling in +x, and the results mapped back.

Under the mirror x' = -x the x-components of vectors change sign and fields are read at -x'.  The
steady slip in +x rolling is s = w - du/dx, in -x rolling s = w + du/dx (the material flows the
other way through the contact); with w = (xi - phi y, eta + phi x) (CONTACT's creepages, relative
velocities over the rolling speed) the mirrored problem is +x rolling with

    xi' = -xi,   eta' = eta,   phi' = -phi,   h'(x', y) = h(-x', y),

and its solution maps back as p_x(x) = -p'_x(-x), p_y(x) = p'_y(-x), p_n(x) = p'_n(-x) (slip and
displacements alike), FX = -FX', FY = FY', MZ = -MZ'.  Consequences (tests/unit/test_inputs.py): for a
geometry symmetric in x the creep forces from xi and eta do not depend on the direction, the
adhesion zone moves to the new leading edge x = -a, and the lateral force from spin changes sign.
A shift (rolling = "shift") has no direction; mirroring it changes nothing.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from conformal.grid import PlanarGrid
from conformal.problem import ContactProblem
from conformal.result import Result, TractionField


def mirror_grid(grid: PlanarGrid) -> PlanarGrid:
    """The grid reflected about x = 0 (element i becomes mx - 1 - i)."""
    return PlanarGrid(grid.mx, grid.my, grid.dx, grid.dy, -(grid.xl + grid.mx * grid.dx), grid.yl)


def mirrored(problem: ContactProblem) -> ContactProblem:
    """The +x rolling problem equivalent to ``problem`` rolling in -x (module docstring)."""
    k = problem.kinematics
    kin = replace(k, xi=-k.xi, phi=-k.phi, fx_rel=None if k.fx_rel is None else -k.fx_rel, direction=1)
    info = dict(problem.info)
    if info.get("rigid_slip") is not None:
        w = np.asarray(info["rigid_slip"], dtype=float)[:, ::-1].copy()
        w[0] *= -1.0
        info["rigid_slip"] = w
    if info.get("mu_scale") is not None:
        info["mu_scale"] = np.asarray(info["mu_scale"])[::-1].copy()
    grid = None if problem.grid is None else mirror_grid(problem.grid)
    h = None if problem.h is None else np.asarray(problem.h)[::-1].copy()
    return replace(problem, kinematics=kin, grid=grid, h=h, info=info)


def _field_back(f: TractionField, grid: PlanarGrid) -> TractionField:
    def back(a, sign=1.0):
        return None if a is None else sign * np.asarray(a)[::-1]

    return TractionField(grid=grid, pn=back(f.pn), px=back(f.px, -1.0), py=back(f.py), status=back(f.status),
                         sx=back(f.sx, -1.0), sy=back(f.sy), un=back(f.un), ux=back(f.ux, -1.0), uy=back(f.uy))


def unmirror(result: Result, problem: ContactProblem) -> Result:
    """The solution of :func:`mirrored` (``result``) mapped back to ``problem`` (rolling in -x)."""
    extra = dict(result.extra)
    for key in ("FX_rel",):
        if extra.get(key) is not None:
            extra[key] = -extra[key]
    extra["direction"] = -1
    if isinstance(extra.get("grid"), dict) and problem.grid is not None:
        extra["grid"] = dict(extra["grid"], xl=problem.grid.xl)
    field = None
    if result.field is not None and problem.grid is not None:
        field = _field_back(result.field, problem.grid)
    return replace(result, FX=-result.FX, MZ=-result.MZ, xi=-result.xi, phi=-result.phi, field=field, extra=extra)
