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


#: the inputs of a problem that are typed fields and, for older readers, also keys of ``info``
INPUT_FIELDS = ("line_contact", "influence_file", "rigid_slip", "mu_scale")


class ProblemInfo(dict):
    """``ContactProblem.info`` as the problem keeps it: the free keys plus the typed inputs
    (:data:`INPUT_FIELDS`, mirrored for readers of ``info["rigid_slip"]``).  A plain mapping
    given as ``info`` (``dict(problem.info)`` changed and passed to :func:`dataclasses.replace`)
    sets the typed inputs it holds; the problem's own ProblemInfo leaves them to the fields."""


@dataclass(frozen=True, eq=False)
class ContactProblem:
    """One contact problem.

    ``h`` is the undeformed distance on ``grid`` (shape (mx, my), mm) before the approach is
    subtracted: the deformed gap is h - approach + u_n.  ``hertz`` is the Hertz solution of the
    quadratic part (None where the geometry is not quadratic).  Exactly one of ``normal_force``
    and ``approach`` is set.

    Per-element inputs (typed; also in ``info`` under the same names for older readers):

    ``line_contact``
        ``[geometry] B = 0``: plane strain on a row of elements (conformal.solvers.line).
    ``influence_file``
        ``[model] influence_file``: the path of the influence numbers (theory exact).
    ``rigid_slip``
        ``[kinematics] rigid_slip``: (2, mx, my) rigid slip added per element (seed Eq. 47).
    ``mu_scale``
        ``[friction] mu_table``: (mx, my) factor on the friction coefficients per element.

    >>> from conformal.specs import Friction, Kinematics, ModelSpec
    >>> from conformal.materials import Material
    >>> p = ContactProblem(Material(82000.0, 0.28, 82000.0, 0.28), Friction(0.3, 0.3), Kinematics(), ModelSpec(),
    ...                    normal_force=1.0, info={"line_contact": True, "position": 3.0})
    >>> p.line_contact, p.info["line_contact"], p.info["position"]
    (True, True, 3.0)
    >>> q = replace(p, line_contact=False)
    >>> q.line_contact, q.info.get("line_contact"), q.info["position"]
    (False, None, 3.0)
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
    #: starting (pn, px, py) on ``grid`` for the iterations (a neighbouring solve on the same grid, e.g.
    #: the previous pass of a wheel-rail balance; px, py may be None); the solution is the same to the
    #: solver's tolerance
    start: tuple[np.ndarray, np.ndarray | None, np.ndarray | None] | None = None
    #: only the totals (FN, FX, FY, MZ, approach, pmax, a, b, creepages) and the traction fields pn, px,
    #: py are wanted: a solve that is never the answer (a loose pass of a wheel-rail balance) skips
    #: the displacements, the patches, CONTACT's totals of energy and the warnings; the numbers it
    #: returns are those of the full solve.  A theory that does not read it computes everything
    lean: bool = False
    line_contact: bool = False
    influence_file: Path | None = None
    rigid_slip: np.ndarray | None = None
    mu_scale: np.ndarray | None = None

    def __post_init__(self):
        info = self.info
        if not isinstance(info, ProblemInfo):       # a mapping from the caller: its typed keys set the fields
            for name in INPUT_FIELDS:
                if name in info:
                    object.__setattr__(self, name, info[name])
        mirrored = {name: getattr(self, name) for name in INPUT_FIELDS
                    if getattr(self, name) is not None and getattr(self, name) is not False}
        free = {k: v for k, v in info.items() if k not in INPUT_FIELDS}
        object.__setattr__(self, "line_contact", bool(self.line_contact))
        object.__setattr__(self, "info", ProblemInfo(free, **mirrored))

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
    h = _load_numbers(path, "[geometry] file")
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
    return [_with_inputs(scene, p) for p in _problems(scene, common)]


def _problems(scene: Scene, common: dict) -> list[ContactProblem]:
    geo, load = scene.geometry, scene.load
    if geo.kind == "quadratic" and geo.B == 0.0:
        return [_line_problem(scene, common)]
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


def _load_numbers(path: Path, key: str) -> np.ndarray:
    """The numbers of ``.npy`` or text (comma or white space separated, '#' comments; one row per
    line); InputError naming ``key`` if the file cannot be read."""
    try:
        if path.suffix == ".npy":
            with open(path, "rb") as fh:
                if fh.read(6) != b"\x93NUMPY":    # numpy would try it as a pickle
                    raise InputError(f"{key}: not a .npy file: {path} (or give the numbers as text)")
            return np.asarray(np.load(path, allow_pickle=False), dtype=float)
        text = path.read_text(encoding="utf-8").replace(",", " ")
        rows = [ln.split("#")[0].split() for ln in text.splitlines()]
        return np.array([[float(v) for v in r] for r in rows if r], dtype=float)
    except InputError:
        raise
    except (OSError, ValueError) as exc:
        raise InputError(f"{key}: cannot read {path}: {exc}") from None


def _read_numbers(path: Path, key: str) -> np.ndarray:
    """A table of numbers (:func:`_load_numbers`), not empty and finite."""
    a = _load_numbers(path, key)
    if a.size == 0 or not np.all(np.isfinite(a)):
        raise InputError(f"{key}: {path.name} is empty or contains NaN or infinite values")
    return a


def read_rigid_slip(path: Path, grid: PlanarGrid) -> np.ndarray:
    """Rigid slip per element, added to the rigid slip of the creepages (seed Eq. 47): ``.npy`` of
    shape (2, mx, my), or text with mx rows (x) of 2 my numbers: w_x of the my columns, then w_y.
    Units as the creepages: steady rolling -, shift mm."""
    key = "[kinematics] rigid_slip"
    a = _read_numbers(Path(path), key)
    if a.ndim == 2 and a.shape == (grid.mx, 2 * grid.my):
        a = np.stack([a[:, : grid.my], a[:, grid.my:]])
    if a.shape != (2, grid.mx, grid.my):
        raise InputError(f"{key}: {Path(path).name} holds {a.shape}; the grid needs (2, {grid.mx}, {grid.my}) "
                         f"(.npy) or {grid.mx} rows of {2 * grid.my} numbers (w_x of each column, then w_y)")
    return a


def read_mu_table(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(s, mu) rows of a friction table: s increasing (mm; y on a planar grid), mu > 0."""
    key = "[friction] mu_table"
    a = _read_numbers(Path(path), key)
    if a.ndim != 2 or a.shape[1] != 2 or a.shape[0] < 1:
        raise InputError(f"{key}: {Path(path).name} must hold rows of two numbers 's mu', got shape {a.shape}")
    s, mu = a[:, 0], a[:, 1]
    if np.any(np.diff(s) <= 0):
        raise InputError(f"{key}: the s values must increase")
    if np.any(mu <= 0):
        raise InputError(f"{key}: every mu must be > 0")
    return s, mu


def _with_inputs(scene: Scene, problem: ContactProblem) -> ContactProblem:
    """Per-element inputs from files: influence numbers (``[model] influence_file``, read by the
    exact theory), the rigid slip (``[kinematics] rigid_slip``) and the friction along the profile (``[friction] mu_table``: mu(y) linear between the rows, constant beyond;
    the bound mu_static p_n and the kinetic mu_kinetic p_n both scale by mu(y)/mu_static)."""
    kin, fr = scene.kinematics, scene.friction
    ifile = dict(scene.model.options).get("influence_file")
    if kin.rigid_slip is None and fr.mu_table is None and ifile is None:
        return problem
    inputs: dict[str, Any] = {}
    if ifile is not None:
        if not isinstance(ifile, str) or not ifile:
            raise InputError(f"[model] influence_file: a file name, got {ifile!r}")
        path = Path(ifile) if Path(ifile).is_absolute() else Path(scene.base_dir) / ifile
        if not path.is_file():
            raise InputError(f"[model] influence_file: no such file: {path}")
        if problem.line_contact:
            raise InputError("[model] influence_file: not for line contact ([geometry] B = 0)")
        inputs["influence_file"] = path
    if kin.rigid_slip is not None:
        inputs["rigid_slip"] = read_rigid_slip(kin.rigid_slip, problem.grid)
    if fr.mu_table is not None:
        if kin.fx_rel is not None or kin.fy_rel is not None:
            raise InputError("[friction] mu_table: prescribed forces (fx_rel, fy_rel) are relative to one mu; "
                             "give the creepages xi, eta with a friction table")
        s, mu = read_mu_table(fr.mu_table)
        mu_y = np.interp(problem.grid.y, s, mu)
        inputs["mu_scale"] = np.broadcast_to(mu_y / fr.mu_static, problem.grid.shape).copy()
    return replace(problem, **inputs)


def _line_problem(scene: Scene, common: dict) -> ContactProblem:
    """Line contact, ``[geometry] B = 0`` (conformal.solvers.line): a row of elements along x, one
    element of 1 mm across, h = A x²; ``normal_force`` is per mm of line length.  The automatic
    grid covers ``scale`` times the 2-D Hertz half-width (Johnson eq. 4.45) with ``n`` elements."""
    from conformal.reference import hertz_2d

    geo, load, g = scene.geometry, scene.load, scene.grid
    if load.normal_force is None:
        raise InputError("[load] approach: line contact ([geometry] B = 0) needs normal_force (N per mm of "
                         "line length); the 2-D approach depends on an arbitrary datum")
    if g.explicit:
        if g.my != 1 or g.dy != 1.0:
            raise InputError(f"[grid] my: line contact ([geometry] B = 0) has one element of dy = 1 mm across "
                             f"the line, got my = {g.my}, dy = {g.dy:g}")
        grid = _grid_from_spec(scene, None)
    else:
        a, _ = hertz_2d(load.normal_force, 1.0 / (2.0 * geo.A), scene.material.E_star)
        grid = PlanarGrid(g.n, 1, 2.0 * g.scale * a / g.n, 1.0, -g.scale * a, -0.5)
    X, _ = grid.mesh()
    return ContactProblem(grid=grid, h=geo.A * X**2, line_contact=True, **common)
