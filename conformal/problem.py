"""From a scene to contact problems: what every model (theory or solver) takes as input.

A :class:`ContactProblem` is one contact patch in its own contact frame (x rolling, y lateral,
n into body 1): materials, friction, the undeformed distance (as curvatures A, B where it is
quadratic, and/or sampled on a planar grid), the load and the kinematics.  Simple scenes give
one problem; a wheel-rail scene gives one per contact patch (conformal.cases.wheelrail).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from conformal.errors import InputError
from conformal.grid import PlanarGrid
from conformal.materials import Material
from conformal.specs import Friction, Kinematics, ModelSpec
from conformal.theories.hertz import HertzContact, hertz_from_curvatures, hertz_from_semiaxes

if TYPE_CHECKING:   # problems_from_scene reads a scene's sections; the problem itself knows no scene
    from conformal.scene import Scene


@dataclass(frozen=True, eq=False)
class ContactProblem:
    """One contact problem.

    ``h`` is the undeformed distance on ``grid`` (shape (mx, my), mm) before the approach is
    subtracted: the deformed gap is h - approach + u_n.  ``hertz`` is the Hertz solution of the
    quadratic part (None where the geometry is not quadratic).  Exactly one of ``normal_force``
    and ``approach`` is set.
    """

    material: Material
    friction: Friction
    kinematics: Kinematics
    model: ModelSpec
    normal_force: float | None = None
    approach: float | None = None
    hertz: HertzContact | None = None
    grid: PlanarGrid | None = None
    h: np.ndarray | None = None
    label: str = "contact"
    info: Mapping[str, Any] = field(default_factory=dict)  # e.g. contact angle, position (wheel-rail)

    def require_hertz(self, who: str) -> HertzContact:
        if self.hertz is None:
            raise InputError(f"[model] theory: {who} needs a quadratic (Hertzian) geometry; "
                             "this problem has a general undeformed distance (use theory = \"exact\")")
        return self.hertz

    def require_grid(self, who: str) -> tuple[PlanarGrid, np.ndarray]:
        if self.grid is None or self.h is None:
            raise InputError(f"[grid]: {who} needs a potential contact grid")
        return self.grid, self.h


def read_table(path: Path, grid: PlanarGrid) -> np.ndarray:
    """Undeformed distance table: ``.npy`` or text (comma or white space separated) with mx rows
    (x) and my columns (y), values in mm, '#' comments allowed."""
    try:
        if path.suffix == ".npy":
            h = np.load(path, allow_pickle=False)
        else:
            text = path.read_text(encoding="utf-8").replace(",", " ")
            rows = [ln.split("#")[0].split() for ln in text.splitlines()]
            h = np.array([[float(v) for v in r] for r in rows if r], dtype=float)
    except (OSError, ValueError) as exc:
        raise InputError(f"[geometry] file: cannot read {path}: {exc}") from None
    if h.shape != grid.shape:
        raise InputError(f"[geometry] file: {path.name} holds a {h.shape} table; the grid is "
                         f"mx x my = {grid.mx} x {grid.my} (one row per x, one column per y)")
    if not np.all(np.isfinite(h)):
        raise InputError(f"[geometry] file: {path.name} contains NaN or infinite values")
    return h


def _grid_from_spec(scene: Scene, hertz: HertzContact | None) -> PlanarGrid:
    g = scene.grid
    if g.explicit:
        xl = g.xl if g.xl is not None else -0.5 * g.mx * g.dx
        yl = g.yl if g.yl is not None else -0.5 * g.my * g.dy
        return PlanarGrid(g.mx, g.my, g.dx, g.dy, xl, yl)
    if hertz is None:
        raise InputError("[grid] mx: an explicit grid (mx, my, dx, dy) is needed for this geometry")
    return PlanarGrid.around_ellipse(hertz.a, hertz.b, n=g.n, scale=g.scale, mx=g.mx, my=g.my)


def problems_from_scene(scene: Scene) -> list[ContactProblem]:
    """The contact problem of a planar scene (quadratic, Hertz or table geometry); a wheel-rail scene
    gives one problem per contact patch through :mod:`conformal.cases.wheelrail`."""
    geo = scene.geometry
    if geo.kind == "wheel_rail":
        raise InputError("[geometry] kind: a wheel_rail scene's problems come from its placement and load "
                         "balance: conformal.cases.wheelrail.problems_from_wheel_rail (or conformal.solve)")
    load = scene.load
    common = dict(material=scene.material, friction=scene.friction, kinematics=scene.kinematics,
                  model=scene.model, normal_force=load.normal_force, approach=load.approach,
                  label=scene.name)
    if geo.kind == "quadratic":
        hz = hertz_from_curvatures(geo.A, geo.B, scene.material, normal_force=load.normal_force,
                                   approach=load.approach)
    elif geo.kind == "hertz":
        hz = hertz_from_semiaxes(geo.a, geo.b, scene.material, normal_force=load.normal_force,
                                 approach=load.approach)
    else:  # table
        grid = _grid_from_spec(scene, None)
        return [ContactProblem(grid=grid, h=read_table(geo.file, grid), **common)]
    grid = _grid_from_spec(scene, hz)
    X, Y = grid.mesh()
    return [ContactProblem(hertz=hz, grid=grid, h=hz.A * X**2 + hz.B * Y**2, **common)]


def with_grid(problem: ContactProblem, grid: PlanarGrid) -> ContactProblem:
    """The same quadratic problem sampled on another grid (for convergence studies)."""
    hz = problem.require_hertz("with_grid")
    X, Y = grid.mesh()
    return replace(problem, grid=grid, h=hz.A * X**2 + hz.B * Y**2)
