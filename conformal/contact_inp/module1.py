"""One case of CONTACT's module 1 (wheel-rail contact), read from a deck.

The input follows the user guide, "Specification of the input file <experim>.inp", subsection
"Module 1": control words CPBTNFS, VLDCMZE {M2}, XHGIAOWR, then the blocks the digits ask for
(solver parameters, friction, material, discretisation, track and rail profile, wheelset geometry
and wheel profile, wheelset position and velocity).  Later cases keep what earlier ones set
(digits 0/1).  Every block is read; what the project's wheel-rail path cannot reproduce is listed
in the case's ``unsupported`` (the case is then refused by name, as in module 3).

>>> from conformal.contact_inp.tokens import Deck
>>> text = '''1203100
...  0022033
...  0000321
...  999 100 30 1 1e-5
...  0.3 0.3
...  0.28 0.28 82000. 82000.
...  0.2 0.2 1.0 90d 8.0 4.0
...  14.0 0 1435.0 0.0
...  'r.prr' 0 1.0 0.0
...  0 0 0 0 0 0
...  1360.0 -70.0 460.0
...  'w.prw' 0 1.0 0.0
...  0.0 0.0 10000. 0.0 0.0 0.0
...  2000. 0.0 0.0 0.0 0.0 -4.348
... '''
>>> c = read_case(Deck("x.inp", text), Module1State(), 1, 1)
>>> c.side, c.rail_file, c.wheel_file, c.position[2], c.unsupported
('right', 'r.prr', 'w.prw', 10000.0, ())
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from conformal.contact_inp.blocks import control_words, damping_and_heat, material_parameters, solver_parameters
from conformal.contact_inp.module3 import _skip_subsurface, unsupported
from conformal.contact_inp.tokens import Deck
from conformal.errors import InputError


@dataclass
class Module1State:
    friction: tuple | None = None
    material: tuple | None = None
    discretisation: tuple | None = None    # DX DS DQREL A_SEP D_SEP D_COMB {D_TURN G_MISS}
    track: tuple | None = None             # GAUGHT GAUGSQ/RAILY0 GAUGWD/RAILZ0 CANT/NOMRADR {CURV}
    rail: tuple | None = None              # 'RFNAME' MIRRORY SCALEYZ SMOOTH {MIRRORZ PRFOPT}
    rail_dev: tuple = (0.0,) * 6
    wheelset: tuple | None = None          # FBDIST FBPOS NOMRADW {YTAPE}
    wheel: tuple | None = None             # 'WFNAME' MIRRORY SCALEYZ SMOOTH {MIRRORZ PRFOPT}
    position: tuple | None = None          # S_WS Y_WS Z_INP ROLL YAW PITCH
    velocity: tuple | None = None          # VS_WS VY_WS VZ_WS VROLL VYAW V_INP
    reasons: dict = field(default_factory=dict)
    case_count: int = 0
    conformal: bool = False                # the last discretisation had D = 4 (conformal approach)
    friction_table: tuple = ()             # V = 1: (ALPHA, FSTAT, FKIN) rows
    blanco: tuple | None = None            # C = 4: (IF_METH, VARIANT) of Blanco's influence correction


@dataclass(frozen=True, eq=False)
class Module1Case:
    number: int
    line: int
    deck: str
    digits: dict
    side: str
    friction: tuple
    material: tuple
    discretisation: tuple
    track: tuple
    rail: tuple
    wheelset: tuple
    wheel: tuple
    position: tuple
    velocity: tuple | None
    rail_dev: tuple
    eps: float | None
    unsupported: tuple = ()
    skipped: tuple = ()
    module: int = 1
    conformal: bool = False            # D = 4: CONTACT's conformal approach (conformal.contact_inp.solve1)
    friction_table: tuple = ()         # V = 1: (ALPHA, FSTAT, FKIN) per surface inclination (rad)
    blanco: tuple | None = None        # C = 4: (IF_METH, VARIANT), Blanco's influence correction (D = 4 only)

    @property
    def rail_file(self) -> str:
        return self.rail[0]

    @property
    def wheel_file(self) -> str:
        return self.wheel[0]


def _profile(deck: Deck, what: str) -> tuple:
    """'FNAME' MIRRORY SCALEYZ SMOOTH {MIRRORZ PRFOPT} and the lines PRFOPT asks for, as the tuple
    (FNAME, MIRRORY, SCALEYZ, SMOOTH, MIRRORZ, PRFOPT, ISMOOTH, ZIGTHRS) (CONTACT's defaults
    MIRRORZ = 0, ISMOOTH = 0, ZIGTHRS = 150 degrees where not given)."""
    from conformal.geometry.miniprof import ZIG_THRESHOLD

    v = deck.mixed("sirr", what, optional="ii")
    mirrorz = v[4] if len(v) > 4 else 0
    prfopt = v[5] if len(v) > 5 else 0
    ismooth, zig = 0, ZIG_THRESHOLD
    if prfopt >= 1:
        opts = deck.reals(5, "ISMOOTH ZIGTHRS KINKHIGH KINKLOW KINKWID", angle=True)
        ismooth, zig = int(round(opts[0])), opts[1]
    if prfopt >= 2:
        deck.reals(2, "ERRHND MAXOMIT", angle=True)
    return (v[0], v[1], v[2], v[3], mirrorz, prfopt, ismooth, zig)


def read_case(deck: Deck, state: Module1State, number: int, line: int, *, ignore_subsurface: bool = False,
              ignore_temperature: bool = False) -> Module1Case:
    """Read the case that follows a ``1`` module line (user guide, module-1 input), update ``state``."""
    d = control_words(deck, "CPBTNFS")
    for letter, ok in {"C1": (0, 1, 4, 5), "C": (0, 1, 2, 3, 4, 9), "L": (0, 1, 2, 3, 4, 6), "M": (0, 1, 2, 3, 4, 5), "V": (0, 1, 2),
                       "H": (0, 1, 3), "G": (0, 1, 2, 3, 4, 5), "S": (0, 1, 2, 3), "Z": (0, 1, 2, 3),
                       "E": (0, 1, 2, 3, 4, 5), "M2": (0, 1, 2)}.items():
        if d[letter] not in ok:
            raise unsupported(deck.name, line, f"module 1, control digit {letter} = {d[letter]}")
    own = []
    conf = d["D"] == 4 or (d["D"] in (0, 1) and state.conformal)     # CONTACT's conformal approach (D = 4)
    for letter, ok, what in (("C1", (0, 1), "rollers"), ("P", (2,), "transient sequences"), ("B", (0,), "traction bound"),
                             ("T", (0, 3), "shift or transient rolling"),
                             ("F", (0, 1) if conf else (0,), "forces prescribed or rail deflection"),
                             ("D", (0, 1, 2, 4), "a discretisation other than planar (D = 2) or conformal (D = 4)"),
                             ("M2", (0,), "damping"),
                             ("H", (0,) if not ignore_temperature else (0, 1, 3), "surface temperatures"),
                             ("E", (0, 1, 2, 3), "flexible wheelset")):
        if d[letter] not in ok:
            own.append(f"module 1, control digit {letter} = {d[letter]} ({what})")
    if d["S"] and not ignore_subsurface:
        own.append(f"control digit S = {d['S']} (subsurface stresses; --ignore-subsurface skips them)")
    inh = state.reasons
    _, eps, solver_notes = solver_parameters(deck, d["G"], module=1, debug=d["X"] == 1)
    L = d["L"]
    nval = {0: 2, 2: 5, 3: 5, 4: 5, 6: 4}.get(L)
    if L != 1:
        if d["V"] == 0:
            state.friction = tuple(deck.reals(nval, "friction parameters", angle=True))
        else:
            nvf = deck.ints(1, "NVF")[0]
            rows = [tuple(deck.reals(nval + 1, "ALPHA/SVF and friction parameters", angle=True)) for _ in range(nvf)]
            state.friction = ("varying",)
            state.friction_table = tuple(rows) if d["V"] == 1 and L == 0 else ()
        if L in (2, 3, 4, 6):
            deck.reals(2, "MEMDST MEM_S0", angle=True)
        if not d["V"]:
            state.friction_table = ()
        reason = None
        if d["V"] == 1 and L == 0:
            reason = None            # per patch (planar) or per row of each strip (D = 4): [friction] angle_table
        elif d["V"]:
            reason = f"module 1, control digit V = {d['V']} (friction varying over the profile)"
        elif L != 0:
            reason = f"module 1, control digit L = {L} (friction law)"
        elif state.friction[0] != state.friction[1]:
            reason = "module 1, FSTAT != FKIN"
        if reason:
            inh["friction"] = reason
        else:
            inh.pop("friction", None)
    elif state.friction is None:
        raise InputError(f"{deck.name}, line {line}: L = 1 keeps the friction of a previous case; there is none")
    C, M = d["C"], d["M"]
    if C >= 2:
        state.blanco = None
        if C == 4:
            state.blanco = tuple(deck.ints(2, "IF_METH VARIANT"))
        state.material = tuple(deck.reals(4, "POISS 1, 2  GG 1, 2", angle=True))
        material_parameters(deck, d["B"], M)
        reason = None
        if C == 4 and (state.blanco[0] not in (0, 1) or state.blanco[1] not in (1, 2, 3, 4)):
            reason = f"module 1, C = 4 with IF_METH = {state.blanco[0]}, VARIANT = {state.blanco[1]} (0-1, 1-4)"
        elif C not in (2, 4):
            reason = f"module 1, control digit C = {C} (influence coefficients)"
        elif M != 0:
            reason = f"module 1, control digit M = {M} (material model)"
        if reason:
            inh["material"] = reason
        else:
            inh.pop("material", None)
    elif state.material is None:
        raise InputError(f"{deck.name}, line {line}: C = {C} keeps the material of a previous case; there is none")
    damping_and_heat(deck, d["M2"], d["H"], M)
    if d["D"] >= 2:
        state.discretisation = tuple(deck.reals(6, "DX DS DQREL A_SEP D_SEP D_COMB", optional=2, angle=True))
        state.conformal = d["D"] == 4
        if d["D"] not in (2, 4):
            inh["discretisation"] = f"module 1, control digit D = {d['D']} (contact search / conformal approach)"
        else:
            inh.pop("discretisation", None)
    elif state.discretisation is None:
        raise InputError(f"{deck.name}, line {line}: D = {d['D']} keeps the discretisation of a previous case; none")
    Z, E = d["Z"], d["E"]
    if Z in (1, 3):
        state.track = tuple(deck.reals(4, "GAUGHT GAUGSQ GAUGWD CANT", optional=1, angle=True))
    if Z == 3:
        state.rail = _profile(deck, "'RFNAME' MIRRORY SCALEYZ SMOOTH")
    if Z in (2, 3):
        state.rail_dev = tuple(deck.reals(6, "DYRAIL DZRAIL DROLLR VYRAIL VZRAIL VROLLR", angle=True))
        if d["F"] == 3:
            deck.reals(4, "KYRAIL FYRAIL KZRAIL FZRAIL", optional=1, angle=True)
    if state.track is None or state.rail is None:
        raise InputError(f"{deck.name}, line {line}: the first case needs the track and rail profile (Z = 3)")
    if E in (3, 5):
        state.wheelset = tuple(deck.reals(3, "FBDIST FBPOS NOMRADW", optional=1, angle=True))
        state.wheel = _profile(deck, "'WFNAME' MIRRORY SCALEYZ SMOOTH")
    if state.wheelset is None or state.wheel is None:
        raise InputError(f"{deck.name}, line {line}: the first case needs the wheelset and wheel profile (E = 3)")
    if E >= 1:
        state.position = tuple(deck.reals(6, "S_WS Y_WS Z_INP ROLL YAW PITCH", angle=True))
    if E >= 2:
        state.velocity = tuple(deck.reals(6, "wheelset velocities or shifts", angle=True))
    if E >= 4:
        deck.reals(12, "flexible wheelset deviations", angle=True)
    if state.position is None:
        raise InputError(f"{deck.name}, line {line}: the first case needs the wheelset position (E >= 1)")
    skipped = solver_notes
    if d["S"]:
        if d["S"] >= 2:
            _skip_subsurface(deck, d["S"])
        if ignore_subsurface:
            skipped = skipped + (f"subsurface stresses (S = {d['S']}) not computed",)
    if d["H"] and ignore_temperature:
        skipped = skipped + (f"surface temperatures (H = {d['H']}) not computed",)
    geo = []
    gaught, gaugsq, gaugwd, cant = state.track[:4]
    single = (conf and gaught <= 0 and gaugsq == 0 and gaugwd == 0 and len(state.track) <= 4
              and tuple(state.wheelset[:2]) == (0.0, 0.0))    # one wheel over one rail, origins together
    if (gaught <= 0 and not single) or (gaught > 0 and gaugsq != 0) or (len(state.track) > 4 and state.track[4] != 0):
        geo.append("module 1, a track given by rail position (GAUGHT <= 0), GAUGSQ != 0 or a curved track")
    for name, prof in (("rail", state.rail), ("wheel", state.wheel)):
        suffix = Path(prof[0]).suffix.lower()
        if suffix in (".slcs", ".slcw"):
            geo.append(f"module 1, a variable {name} profile (slices file {Path(prof[0]).name})")
        elif suffix not in (".prr", ".prw", ".ban", ".whl"):
            geo.append(f"module 1, {name} profile {Path(prof[0]).name} (a 2-column table: only .prr, .prw, "
                       ".ban and .whl are read)")
        if prof[2] != 1.0:
            geo.append(f"module 1, {name} profile option SCALEYZ = {prof[2]:g} (only 1)")
        if prof[3] > 0 and prof[6] not in (0, 1):
            geo.append(f"module 1, {name} profile option ISMOOTH = {prof[6]} (smoothing spline with a third-order "
                       "penalty)")
    if state.blanco is not None and not conf:
        geo.append("module 1, control digit C = 4 (Blanco's influence correction; only with the conformal approach "
                   "D = 4)")
    if any(v != 0.0 for v in state.rail_dev):
        geo.append("module 1, rail deviations DYRAIL .. VROLLR")
    if len(state.wheelset) > 3 and state.wheelset[3] != 0:
        geo.append("module 1, YTAPE")
    dx, ds = state.discretisation[0], state.discretisation[1]
    if abs(dx - ds) > 1e-12 and not conf:
        geo.append(f"module 1, DX = {dx:g} != DS = {ds:g} (square elements only with D = 2)")
    vel = state.velocity
    if vel is not None and (vel[2] != 0.0):
        geo.append("module 1, a vertical wheelset velocity VZ_WS")
    state.case_count += 1
    return Module1Case(number=number, line=line, deck=deck.name, digits=d, side="left" if d["C1"] in (0, 4) else "right",
                       friction=state.friction, material=state.material, discretisation=state.discretisation,
                       track=state.track, rail=state.rail, wheelset=state.wheelset, wheel=state.wheel,
                       position=state.position, velocity=state.velocity, rail_dev=state.rail_dev, eps=eps,
                       unsupported=tuple(own) + tuple(inh.values()) + tuple(geo), skipped=skipped,
                       conformal=conf, friction_table=state.friction_table, blanco=state.blanco)
