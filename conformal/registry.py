"""The model registry: what each ``[model] theory`` is, which keys it reads, what it accepts and
what it costs, declared once with one :class:`Model` call per model.

Scene validation (:mod:`conformal.scene`: the theory names, the ``[model]`` keys and their
checks, the combinations a theory accepts, the memory estimate), the CLI's ``--theory`` help, the
wheel-rail cases' dispatch (capability queries, not theory names) and the reference documentation
of the scene keys (:func:`reference_markdown`) are all read from here.  The solve functions are
named by each declaration (``solve="conformal.theories.hertz:solve"``) and loaded by
:mod:`conformal.models`.

The registry sits below the scene layer (pyproject's import contract): it holds data only, so a
model's declaration lives here and its ``solve(problem) -> Result`` in its own module above the
solvers layer, named by a dotted string.  The import contract sees these names as imports of
:mod:`conformal.models` (tests/unit/test_architecture.py adds them to the import graph).  Adding
a model to the package: its module (with ``solve``) and one :class:`Model` line in :data:`MODELS`.
A model outside the package (``Model(..., solve=solve)``, the function itself) is added with one
line, :meth:`Registry.with_model`.

Options nest by method in scene files: ``[model.fe] order = 2`` is the flat key ``fe_order = 2``
(both spellings are accepted, :func:`flatten_model_table`).

>>> MODELS["exact"].accepts(HISTORY), MODELS["fastsim"].accepts(HISTORY)
(True, False)
>>> MODELS.accepting(CURVED_STRIP)
('conformal',)
>>> MODELS.option("fe_order").default, MODELS.option("fe_order").group
(1, 'fe')
"""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Iterator, Mapping

from conformal.errors import InputError

# ----------------------------------------------------------------------------- capabilities
#: ``[[history]]`` load steps with memory (conformal.solvers.history)
HISTORY = "history"
#: ``[kinematics] rigid_slip``: a rigid slip per element read from a file
RIGID_SLIP = "rigid_slip"
#: ``[friction] mu_table``: a friction coefficient per element read from a file
MU_TABLE = "mu_table"
#: ``[model] influence_file``: influence numbers read from a file (conformal.influence.contact_file)
INFLUENCE_FILE = "influence_file"
#: line contact (``[geometry] B = 0``): plane strain on the half-plane (conformal.solvers.line)
LINE_CONTACT = "line_contact"
#: ``[load] load_angle``: the wheel pressed along a direction other than vertical
LOAD_ANGLE = "load_angle"
#: ``[load] approach_along``: an approach along the load direction
APPROACH_ALONG = "approach_along"
#: ``[model] influence = "halfspace_planar"`` (CONTACT's conformal approach, D = 4 with C3 = 2)
PLANAR_HALFSPACE = "halfspace_planar"
#: the tangential problem is solved (creepages give FX, FY, MZ); without it the model is normal only
TANGENTIAL = "tangential"
#: wheel-rail scenes: the normal problem is solved on the grid (not from a Hertz estimate)
GRID = "grid"
#: wheel-rail balance: a previous pass's pressures on the same grid start the iterations
WARM_START = "warm_start"
#: wheel-rail scenes: one curved strip per wheel over every patch (conformal.cases.conformal)
CURVED_STRIP = "curved_strip"
#: wheel-rail and quadratic scenes: meshed FE bodies in contact (conformal.cases.fe_contact)
FE_BODIES = "fe_bodies"
#: ``conformal solve --vtu``: tractions or pressures written on the surfaces
VTU = "vtu"
#: a conformal contact is solved as such: no warning about a planar theory on a curved patch
CONFORMAL_GEOMETRY = "conformal_geometry"
#: ``[model] influence = "fe"``: FE influence numbers of the real bodies (precomputed for sweeps,
#: FE body stresses)
FE_INFLUENCE = "fe_influence"

CAPABILITIES = (HISTORY, RIGID_SLIP, MU_TABLE, INFLUENCE_FILE, LINE_CONTACT, LOAD_ANGLE, APPROACH_ALONG,
                PLANAR_HALFSPACE, TANGENTIAL, GRID, WARM_START, CURVED_STRIP, FE_BODIES, VTU, CONFORMAL_GEOMETRY,
                FE_INFLUENCE)

_TYPES = {"int": "whole number", "float": "number", "bool": "true | false", "str": "string", "path": "file",
          "floats": "list of numbers"}


# ----------------------------------------------------------------------------- declarations
@dataclass(frozen=True)
class Option:
    """One ``[model]`` key of a model or a method.

    Parameters
    ----------
    name : str
        The key within its method (``order`` in ``[model.fe]``) or, without a method, the flat key.
    type : str
        One of ``int``, ``float``, ``bool``, ``str``, ``path``, ``floats``.
    default : Any
        The value used when the key is missing (None: computed, see ``doc``).
    unit : str
        Unit of the value ("" for none), e.g. ``mm``, ``mm³/N``.
    doc : str
        One line: what the key sets.
    choices : tuple, optional
        The values allowed (strings).
    minimum : float, optional
        The smallest value allowed (whole numbers and numbers).
    length : int, optional
        ``floats``: the number of values.
    group : str, optional
        The method the key belongs to (``fe``, ``fe_contact``): set by :class:`Method`.
    checked : bool
        The value is checked when the scene is read (else by the method that reads it, when it runs).
    positive : bool
        Numbers: the value must be > 0 (``minimum`` is inclusive).
    """

    name: str
    type: str
    default: Any = None
    unit: str = ""
    doc: str = ""
    choices: tuple = ()
    minimum: float | None = None
    length: int | None = None
    group: str | None = None
    prefix: str = ""
    checked: bool = True
    positive: bool = False

    @property
    def key(self) -> str:
        """The flat ``[model]`` key (``fe_order`` for ``order`` in ``[model.fe]``)."""
        return self.prefix + self.name

    def problem(self, value: Any) -> str | None:
        """What is wrong with ``value`` (None: nothing); ``checked = False`` options pass here."""
        if not self.checked:
            return None
        v = value
        if self.type == "int":
            if isinstance(v, bool) or not isinstance(v, int):
                return f"must be a whole number >= {self.minimum or 0:g}, got {v!r}"
        elif self.type == "float":
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                return f"must be a number, got {v!r}"
        elif self.type == "bool":
            return None if isinstance(v, bool) else f"must be true or false, got {v!r}"
        elif self.type in ("str", "path"):
            if not isinstance(v, str):
                return f"must be a string, got {v!r}"
        elif self.type == "floats":
            ok = (isinstance(v, (list, tuple)) and (self.length is None or len(v) == self.length) and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                and (self.minimum is None or x > self.minimum) for x in v))
            return None if ok else f"must be {self.length} numbers > {self.minimum or 0:g} ({self.doc}), got {v!r}"
        if self.choices and v not in self.choices:
            return f"must be one of {', '.join(repr(c) for c in self.choices)}, got {v!r}"
        if self.minimum is not None and self.type in ("int", "float") and v < self.minimum:
            return f"must be >= {self.minimum:g}, got {v}"
        if self.positive and self.type in ("int", "float") and not v > 0:
            return f"must be > 0, got {v}"
        return None



@dataclass(frozen=True)
class Method:
    """Options that belong to a method, not to one theory: written ``[model.<name>]`` in a scene
    (or flat with ``prefix``, the older spelling), e.g. the FE influence numbers (``[model.fe]``)."""

    name: str
    prefix: str
    doc: str
    options: tuple[Option, ...]

    def __post_init__(self):
        object.__setattr__(self, "options", tuple(replace(o, group=self.name, prefix=self.prefix)
                                                  for o in self.options))


@dataclass(frozen=True)
class Model:
    """One ``[model] theory``: its name, keys, capabilities and memory per grid element.

    Parameters
    ----------
    name : str
        The value of ``[model] theory``.
    summary : str
        One line: what the model solves (seed equations, reference).
    options : tuple of Option
        The model's own ``[model]`` keys (besides the common ones, :data:`COMMON`).
    methods : tuple of str
        Names of the :class:`Method` s whose keys the model reads (``fe``).
    capabilities : frozenset of str
        What it accepts or does (:data:`CAPABILITIES`).
    bytes_per_element : float
        Memory per grid element (arrays it allocates).
    bytes_dense_y : float
        Memory of dense blocks along y: ``bytes_dense_y * mx * my**2`` more (the conformal strips).
    solve : str or callable
        Where ``solve(problem) -> Result`` is: ``"module:function"`` (the package's models, loaded
        when :mod:`conformal.models` is imported, from a layer below it) or the function itself
        (a model outside the package).
    """

    name: str
    summary: str
    options: tuple[Option, ...] = ()
    methods: tuple[str, ...] = ()
    capabilities: frozenset = frozenset()
    bytes_per_element: float = 900.0
    bytes_dense_y: float = 0.0
    solve: str | Callable | None = field(default=None, compare=False)

    def __post_init__(self):
        unknown = set(self.capabilities) - set(CAPABILITIES)
        if unknown:
            raise ValueError(f"model {self.name!r}: unknown capabilities {sorted(unknown)}")
        if isinstance(self.solve, str) and not all(self.solve.partition(":")):
            raise ValueError(f"model {self.name!r}: solve = {self.solve!r} is not \"module:function\"")
        object.__setattr__(self, "capabilities", frozenset(self.capabilities))

    @property
    def solve_module(self) -> str | None:
        """The module named by ``solve = "module:function"`` (None for a function given itself)."""
        return self.solve.partition(":")[0] if isinstance(self.solve, str) else None

    def accepts(self, capability: str) -> bool:
        """Whether the model has ``capability`` (one of :data:`CAPABILITIES`)."""
        if capability not in CAPABILITIES:
            raise ValueError(f"unknown capability {capability!r}")
        return capability in self.capabilities

    @property
    def normal_only(self) -> bool:
        """The model solves the normal problem only (no tangential tractions)."""
        return TANGENTIAL not in self.capabilities

    def grid_bytes(self, mx: int, my: int) -> float:
        """Estimated memory (bytes) of an mx x my grid."""
        return float(mx) * float(my) * self.bytes_per_element + self.bytes_dense_y * float(mx) * float(my) ** 2


# ----------------------------------------------------------------------------- the registry
@dataclass(frozen=True)
class Registry:
    """The models and methods by name (immutable; :meth:`with_model` gives an extended copy)."""

    models: tuple[Model, ...]
    methods: tuple[Method, ...] = ()

    def __post_init__(self):
        names = [m.name for m in self.models]
        if len(set(names)) != len(names):
            raise ValueError(f"models named twice: {sorted(n for n in set(names) if names.count(n) > 1)}")
        known = {m.name for m in self.methods}
        for m in self.models:
            if set(m.methods) - known:
                raise ValueError(f"model {m.name!r}: unknown methods {sorted(set(m.methods) - known)}")
        keys = [o.key for o in self.all_options()]
        dup = sorted(k for k in set(keys) if keys.count(k) > 1
                     and len({(o.type, o.group) for o in self.all_options() if o.key == k}) > 1)
        if dup:
            raise ValueError(f"[model] keys declared differently by two models: {dup}")

    def __getitem__(self, name: str) -> Model:
        for m in self.models:
            if m.name == name:
                return m
        raise KeyError(name)

    def __contains__(self, name: object) -> bool:
        return any(m.name == name for m in self.models)

    def __iter__(self) -> Iterator[Model]:
        return iter(self.models)

    @property
    def names(self) -> tuple[str, ...]:
        """The theory names, in declaration order."""
        return tuple(m.name for m in self.models)

    def with_model(self, model: Model) -> "Registry":
        """The registry with one more model (the one line that adds a model)."""
        return replace(self, models=self.models + (model,))

    def method(self, name: str) -> Method:
        for m in self.methods:
            if m.name == name:
                return m
        raise KeyError(name)

    def accepting(self, capability: str) -> tuple[str, ...]:
        """Names of the models with ``capability``."""
        return tuple(m.name for m in self.models if m.accepts(capability))

    def quoted(self, capability: str) -> str:
        """The names of the models with ``capability``, quoted for a message: '"exact"' or
        '"exact" or "conformal"'."""
        return " or ".join(f'"{n}"' for n in self.accepting(capability))

    def accepts(self, theory: str, capability: str) -> bool:
        """Whether ``theory`` has ``capability`` (False for an unknown theory)."""
        return theory in self and self[theory].accepts(capability)

    def all_options(self) -> list[Option]:
        """Every model and method option (a key shared by models appears once per model)."""
        return [o for m in self.models for o in m.options] + [o for me in self.methods for o in me.options]

    def options(self) -> dict[str, Option]:
        """Every ``[model]`` key a scene may give (flat spelling) -> its first declaration."""
        out: dict[str, Option] = {}
        for o in self.all_options():
            out.setdefault(o.key, o)
        return out

    def option(self, key: str) -> Option:
        """The declaration of the flat ``[model]`` key."""
        return self.options()[key]

    def readers(self, key: str) -> tuple[str, ...]:
        """Names of the models that read the flat ``[model]`` key."""
        out = []
        for m in self.models:
            keys = {o.key for o in m.options} | {o.key for me in m.methods for o in self.method(me).options}
            if key in keys:
                out.append(m.name)
        return tuple(out)

    def grid_bytes(self, mx: int, my: int, theory: str) -> float:
        """Estimated memory (bytes) of an mx x my grid with ``theory`` (900 bytes per element for
        a theory the registry does not know)."""
        if theory in self:
            return self[theory].grid_bytes(mx, my)
        return float(mx) * float(my) * 900.0

    def theory_help(self) -> str:
        """The CLI's ``--theory`` help: every name with its summary."""
        return "override [model] theory, one of: " + ", ".join(self.names)


def _did_you_mean(word: str, known) -> str:
    close = difflib.get_close_matches(word, list(known), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def flatten_model_table(raw: Mapping[str, Any], registry: "Registry | None" = None) -> dict[str, Any]:
    """A ``[model]`` table with its method sub-tables (``[model.fe]``, ``[model.fe_contact]``)
    written as flat keys (``fe_order``, ``fec_n``), the form the scene keeps.

    >>> flatten_model_table({"theory": "conformal", "fe": {"order": 2, "h_patch": 1.5}})
    {'theory': 'conformal', 'fe_order': 2, 'fe_h_patch': 1.5}
    >>> flatten_model_table({"fe": {"order": 2}, "fe_order": 1})
    Traceback (most recent call last):
    ...
    conformal.errors.InputError: [model.fe] order: given twice (also as [model] fe_order)
    """
    registry = registry or MODELS
    out: dict[str, Any] = {}
    nested = []
    for k, v in raw.items():
        if k in {me.name for me in registry.methods} and isinstance(v, Mapping):
            nested.append((registry.method(k), v))
        else:
            out[k] = v
    for method, table in nested:
        names = {o.name: o for o in method.options}
        for k, v in table.items():
            if k not in names:
                raise InputError(f"[model.{method.name}] {k}: unknown key{_did_you_mean(k, names)} "
                                 f"(known: {', '.join(names)})")
            flat = names[k].key
            if flat in out:
                raise InputError(f"[model.{method.name}] {k}: given twice (also as [model] {flat})")
            out[flat] = v
    return out


# ----------------------------------------------------------------------------- the built-in models
#: the ``[model]`` keys every theory has (conformal.specs.ModelSpec)
COMMON = (
    Option("theory", "str", "fastsim", "", "the model that solves the contact (see below)"),
    Option("bound", "str", "parabolic", "", "FASTSIM's traction bound", choices=("parabolic", "elliptic")),
    Option("influence", "str", "halfspace", "", "influence numbers: half-space with the element frames turned "
           "by the contact angles, \"halfspace_planar\" (CONTACT's conformal approach; theory conformal) or "
           "\"halfspace_blanco\" (with Blanco-Lorenzo's angle correction, CONTACT's C3 = 4; theory conformal) or "
           "\"fe\" (finite elements of the real bodies, [model.fe])",
           choices=("halfspace", "halfspace_planar", "halfspace_blanco", "fe")),
    Option("tol", "float", 1e-6, "", "relative change of the tractions that stops the iterations (<= 1e-2)"),
    Option("maxit", "int", 1000, "", "largest number of iterations", minimum=1),
    Option("layer_flexibility", "float", 0.0, "mm/(N/mm²)", "FASTSIM contamination layer (seed Eqs. 34-36)"),
)

_MAXOUT = Option("maxout", "int", 50, "", "outer (normal-tangential) iterations", minimum=1)

FE = Method("fe", "fe_", "FE influence numbers of the real wheel and rail ([model] influence = \"fe\", "
            "conformal.influence.fe); checked when the scene is read", options=(
                Option("method", "str", "split", "", "\"split\" | \"direct\"", choices=("split", "direct")),
                Option("order", "int", 1, "", "element order", choices=(1, 2)),
                Option("h_patch", "float", 2.0, "element sizes", "element size on the patch, relative to the "
                       "contact element size", positive=True),
                Option("h_load", "float", 0.5, "element sizes", "element size of the loaded column", positive=True),
                Option("growth", "float", 0.35, "", "element growth rate", positive=True),
                Option("h_max", "float", 0.2, "body depths", "largest element, relative to the body margin",
                       positive=True),
                Option("conform", "str", "column", "", "conforming mesh: \"all\" | \"column\" | \"none\"",
                       choices=("all", "column", "none")),
                Option("body_size", "float", 16.0, "patch sizes", "body margin around the patch", positive=True),
                Option("solver", "str", "auto", "", "linear solver: \"auto\" | \"pardiso\" | \"splu\" | \"amg\"",
                       choices=("auto", "pardiso", "splu", "amg")),
                Option("collocation", "str", "centre", "", "collocation rule: \"centre\" | \"average\"",
                       choices=("centre", "average")),
                Option("far_field", "str", "halfspace", "", "far-field boundary condition: \"halfspace\" | "
                       "\"clamped\"", choices=("halfspace", "clamped")),
                Option("closure", "str", "extend", "", "a profile ending inside the body: \"extend\" (straight, "
                       "slabs limited) | \"straight\" | \"cut\" | \"section\" (the real rail and wheel sections)",
                       choices=("extend", "straight", "cut", "section")),
                Option("h_wall", "float", 0.25, "wall thicknesses", "closure \"section\": largest element in a "
                       "wall of the section (web, foot, rim), relative to its local thickness", positive=True),
            ))

FE_CONTACT = Method("fe_contact", "fec_", "meshed bodies of the direct FE contact (theory fe_contact, "
                    "conformal.fe_contact.problems); checked when the scene is read (the largest fec_n when the "
                    "bodies are meshed)", options=(
                        Option("n", "int", 4, "", "elements per (smaller) contact semi-axis on the contact surface",
                               minimum=1),
                        Option("h", "float", None, "mm", "element size on the contact surface (overrides n)",
                               positive=True),
                        Option("order", "int", 2, "", "1 (linear) or 2 (quadratic) tetrahedra", choices=(1, 2)),
                        Option("growth", "float", 0.3, "1/mm", "increase of the element size per mm away from the "
                               "contact", positive=True),
                        Option("h_max", "float", 0.25, "body depths", "largest element, relative to the body depth",
                               positive=True),
                        # 1: size-converged with the half-space far field (studies/fe_contact_body_size.py:
                        # the deep pair's FN within 0.4 % of its large-body limit, inside the mesh scatter)
                        Option("body_size", "float", 1.0, "patch sizes", "margin of the bodies beyond the contact "
                               "patch (1: FN within 0.4 % of the large-body limit with the half-space far field)",
                               positive=True),
                        Option("patch", "float", 1.3, "semi-axes", "fine patch extent in contact semi-axes",
                               positive=True),
                        Option("far_field", "str", "halfspace", "", "cut faces: \"halfspace\" | \"clamped\"",
                               choices=("halfspace", "clamped")),
                        Option("solver", "str", "auto", "", "\"auto\" | \"splu\" | \"pardiso\"",
                               choices=("auto", "splu", "pardiso")),
                        Option("estimate", "str", "halfspace", "", "wheel-rail: contact size from a half-space "
                               "solve (\"halfspace\") or the grid (\"grid\")", choices=("halfspace", "grid")),
                        Option("body", "str", "disc", "", "wheel-rail bodies: \"disc\" | \"section\" (ground "
                               "truth) | \"block\"", choices=("disc", "section", "block")),
                        Option("section_size", "float", 20.0, "patch sizes", "\"section\": rail ends and wheel "
                               "sector cuts beyond the patch", positive=True),
                        Option("section_h_max", "float", 12.0, "mm", "\"section\": largest element", positive=True),
                        Option("slave", "float", 1.6, "", "wheel-rail (\"disc\" and \"section\"): contact candidates "
                               "= the patch enlarged by this factor", minimum=1.0),
                    ))

_PLANAR = frozenset({TANGENTIAL})

#: the package's models, one :class:`Model` line each (``solve``: where its function is, conformal.models)
MODELS = Registry(models=(
    Model("hertz", "Hertz theory of non-conformal contact (Hertz 1882; Johnson 1985, §4.2); normal problem only",
          bytes_per_element=48, solve="conformal.theories.hertz:solve"),
    Model("linear", "Kalker's linear theory of rolling contact (seed Eq. 13; Kalker 1967)",
          options=(Option("require_c33", "bool", False, "", "compute C33 also without spin"),),
          capabilities=_PLANAR, bytes_per_element=48, solve="conformal.theories.linear:solve"),
    Model("empirical", "Kalker's empirical creep-force law (seed Eqs. 18, 20)",
          options=(Option("creep_coefficients", "str", "kalker", "", "creep coefficients",
                          choices=("kalker", "elliptic")),), capabilities=_PLANAR, bytes_per_element=48,
          solve="conformal.theories.empirical:solve"),
    Model("johnson_vermeulen", "Johnson-Vermeulen creep-force law (seed Eq. 19)",
          options=(Option("creep_coefficients", "str", "elliptic", "", "creep coefficients",
                          choices=("kalker", "elliptic")),), capabilities=_PLANAR, bytes_per_element=48,
          solve="conformal.theories.empirical:solve"),
    Model("fastsim", "Kalker's simplified theory, algorithm FASTSIM (seed Eqs. 21-36)",
          options=(Option("n", "int", 40, "", "number of strips", minimum=4),
                   Option("flexibilities", "floats", None, "mm³/N", "the flexibilities L1, L2, L3 (default: "
                          "from Kalker's coefficients, seed Eq. 27)", length=3, minimum=0),
                   Option("discretisation", "str", "midpoint", "", "where the strips are sampled",
                          choices=("midpoint", "contact"))),
          capabilities=_PLANAR, bytes_per_element=240, solve="conformal.theories.fastsim:solve"),
    Model("exact", "Kalker's exact theory on a planar grid (seed Eqs. 45-49; Kalker 1990)",
          options=(_MAXOUT,
                   Option("influence_file", "path", None, "", "influence numbers read from a file "
                          "(conformal.influence.contact_file)")),
          capabilities=frozenset({TANGENTIAL, HISTORY, RIGID_SLIP, MU_TABLE, INFLUENCE_FILE, LINE_CONTACT, GRID,
                                  WARM_START}), bytes_per_element=900, solve="conformal.solvers.exact:solve"),
    Model("conformal", "conformal contact on a curved strip (Li 2002; seed Eqs. 45-49 on the curved surface)",
          options=(_MAXOUT,
                   Option("max_mx", "int", 200, "", "largest number of strip elements along x", minimum=4),
                   Option("max_ms", "int", 200, "", "largest number of strip elements along s", minimum=4),
                   Option("creepage", "str", None, "", "creepages on the strip: \"surface\" (default) | "
                          "\"reference\" | \"wheel_surface\" (CONTACT's rigid slip; default of halfspace_planar)",
                          choices=("surface", "reference", "wheel_surface")),
                   Option("blanco_variant", "int", 3, "", "influence = \"halfspace_blanco\": CONTACT's VARIANT "
                          "(conformal.influence.blanco)", choices=(1, 2, 3, 4)),
                   Option("blanco_method", "str", "full", "", "influence = \"halfspace_blanco\": \"full\" "
                          "(CONTACT's IF_METH = 1) | \"linear\" (IF_METH = 0)", choices=("full", "linear"))),
          methods=("fe",),
          capabilities=frozenset({TANGENTIAL, LOAD_ANGLE, APPROACH_ALONG, PLANAR_HALFSPACE, GRID, CURVED_STRIP, VTU,
                                  CONFORMAL_GEOMETRY, FE_INFLUENCE}),
          bytes_per_element=900, bytes_dense_y=2 * 9 * 16, solve="conformal.solvers.conformal:solve"),
    Model("table", "creep forces from a creep-force table (conformal.tables)",
          options=(Option("table", "path", None, "", "the creep-force table file (\"default\": the package's)"),),
          capabilities=_PLANAR, bytes_per_element=48, solve="conformal.tables.model:solve"),
    Model("fe_contact", "direct FE contact of the meshed bodies (conformal.fe_contact); normal problem only",
          methods=("fe_contact",), capabilities=frozenset({FE_BODIES, VTU, CONFORMAL_GEOMETRY}),
          bytes_per_element=900, solve="conformal.fe_contact.problems:solve"),
), methods=(FE, FE_CONTACT))


# ----------------------------------------------------------------------------- documentation
def _fmt(v: Any) -> str:
    if v is None:
        return "--"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    return f"{v:g}" if isinstance(v, float) else str(v)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _table(options, key=lambda o: o.key) -> list[str]:
    rows = ["| key | type | default | unit | meaning |", "|---|---|---|---|---|"]
    for o in options:
        choices = " | ".join(_fmt(c) for c in o.choices)
        doc = o.doc + (f" ({choices})" if o.choices and '"' not in o.doc else "")
        rows.append(f"| `{key(o)}` | {_cell(_TYPES[o.type])} | {_fmt(o.default)} | {o.unit} | {_cell(doc)} |")
    return rows


def reference_markdown(registry: Registry | None = None, sections: Mapping[str, list] | None = None) -> str:
    """The ``[model]`` reference as markdown (for the documentation site): the common keys, each
    theory with its keys and capabilities, each method's ``[model.<method>]`` keys.  ``sections``:
    further ``{section: [(key, type, default, unit, doc), ...]}`` tables put first
    (:func:`conformal.scene.reference_markdown` gives the other scene sections).

    >>> md = reference_markdown()
    >>> "| `fe_order` |" in md or "| `order` |" in md, "### theory `exact`" in md
    (True, True)
    """
    registry = registry or MODELS
    out = ["# Scene keys", ""]
    for name, rows in (sections or {}).items():
        out += [f"## [{name}]", "", "| key | type | default | unit | meaning |", "|---|---|---|---|---|"]
        out += [f"| `{k}` | {t} | {_fmt(d)} | {u} | {_cell(doc)} |" for k, t, d, u, doc in rows]
        out.append("")
    out += ["## [model]", "", "Keys of every theory:", ""] + _table(COMMON) + [""]
    for m in registry.models:
        out += [f"### theory `{m.name}`", "", m.summary + ".", ""]
        caps = sorted(m.capabilities)
        out.append(f"Accepts: {', '.join(caps) if caps else 'none'}; memory: {m.bytes_per_element:g} bytes per "
                   f"grid element" + (f" + {m.bytes_dense_y:g} mx my² (dense blocks along s)" if m.bytes_dense_y
                                      else "") + ".")
        out.append("")
        if m.options:
            out += _table(m.options) + [""]
        for me in m.methods:
            out += [f"Reads the keys of `[model.{me}]`.", ""]
    for me in registry.methods:
        out += [f"### [model.{me.name}]", "", me.doc + f"; flat spelling: `[model] {me.prefix}<key>`.", ""]
        out += _table(me.options, key=lambda o: o.name) + [""]
    return "\n".join(out).rstrip() + "\n"
