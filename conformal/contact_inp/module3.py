"""One case of CONTACT's module 3 (basic Hertzian and non-Hertzian contact), read from a deck.

The input of a case follows the user guide, "Specification of the input file <experim>.inp",
subsection "Module 3": control words PBTNFS, LDCMZE {M2}, XHGIAOWR, then the blocks that the
digits ask for.  Later cases inherit what earlier cases set (digits 0/1 "maintain"): the reader
keeps one :class:`Module3State` per deck and returns a frozen copy for every case.

What the reader supports is what the project's solvers can reproduce; any other digit value
raises :class:`Unsupported` naming the digit (the CLI prints it as one line, exit 2).

>>> from conformal.contact_inp.tokens import Deck
>>> text = '''  200100  PBTNFS
...   022020  LDCMZE
...  0000011  HGIAOWR
...   100 100 30 1 1e-6
...   100. 0 0 0   FN, CKSI, CETA, CPHI
...   0.3 0.3
...   0.28 0.28 82000 82000
...   -1
...   20 20 0.001 0.001 1.1
... '''
>>> st = Module3State()
>>> case = read_case(Deck("x.inp", text), st, 1, 1)
>>> case.digits["T"], case.fn, case.grid_spec
(0, 100.0, ('hertz', -1, 20, 20, (0.001, 0.001, 1.1)))
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from conformal.errors import InputError
from conformal.scene import check_grid_memory
from conformal.contact_inp.blocks import control_words, damping_and_heat, material_parameters, solver_parameters
from conformal.contact_inp.tokens import Deck


class Unsupported(InputError):
    """A CONTACT digit or feature this reader does not support."""


def unsupported(deck_name: str, line: int, what: str) -> Unsupported:
    return Unsupported(f"{deck_name}, line {line}: not supported: {what}")


# meanings of the digit values that are refused, for the error line
_MEANING = {
    ("B", 1): "elastic layer", ("B", 2): "elliptical traction bound", ("B", 3): "parabolic traction bound",
    ("B", 4): "SDEC", ("B", 5): "KPEC", ("B", 6): "modified ANALYN",
    ("S", 1): "subsurface stresses", ("S", 2): "subsurface stresses", ("S", 3): "subsurface stresses",
    ("L", 2): "velocity-dependent friction", ("L", 3): "velocity-dependent friction",
    ("L", 4): "velocity-dependent friction", ("L", 5): "velocity-dependent friction (Polach)",
    ("L", 6): "temperature-dependent friction",
    ("C", 3): "bilinear half-space influence coefficients", ("C", 4): "Blanco angle correction",
    ("C", 5): "layered half-space",
    ("M", 1): "viscoelastic materials", ("M", 2): "FASTSIM with one flexibility",
    ("M", 3): "FASTSIM (modified)", ("M", 4): "interfacial layer / plasticity", ("M", 5): "FaStrip",
    ("M", 6): "FaStrip (original)", ("M", 7): "FaStrip (full sliding)",
    ("H", 1): "surface temperatures; --ignore-temperature skips them",
    ("H", 3): "surface temperatures; --ignore-temperature skips them",
    ("M2", 1): "damping", ("M2", 2): "damping",
    ("E", 2): "extra rigid-slip term -(x-xo) phi", ("E", 3): "extra rigid-slip term (y-yo) phi",
    ("V", 1): "friction varying across the rail", ("V", 2): "friction varying along the track",
    ("P", 1): "new time step for the normal part only",
}


@dataclass
class Module3State:
    """What a module-3 case leaves for the next ones (None: not yet set)."""

    friction: tuple | None = None          # (fstat, fkin)
    rolling: tuple | None = None           # (chi, dq, veloc)
    material: tuple | None = None          # (nu1, nu2, g1, g2)
    inflcf: int | None = None              # C digit in force: 2 or 9
    cfname: str | None = None
    grid_spec: tuple | None = None         # ('hertz', ipotcn, mx, my, params) | ('grid', ipotcn, mx, my, params)
    geometry: tuple | None = None          # (ibase, params or h array)
    exrhs: np.ndarray | None = None        # (npot, 2) extra rigid slip
    case_count: int = 0
    reasons: dict = field(default_factory=dict)   # unsupported data kept for later cases, by kind
    hertz_load: tuple | None = None        # (FN, PEN) of the case that set a Hertzian grid (D = 2)
    mater_params: tuple = ()               # FLX K0_MF ALFAMF BETAMF (M = 2) or K0_MF ALFAMF BETAMF (M = 3)
    friction_rows: tuple = ()              # V = 3: (FSTAT, FKIN) per grid row (y index)


@dataclass(frozen=True, eq=False)
class Module3Case:
    """The resolved input of one module-3 case (everything inherited filled in)."""

    number: int
    line: int
    deck: str
    digits: dict
    pen: float | None
    fn: float | None
    cksi: float | None
    ceta: float | None
    fxrel: float | None
    fyrel: float | None
    cphi: float
    spin_centre: tuple
    friction: tuple
    rolling: tuple | None
    material: tuple
    inflcf: int
    cfname: str | None
    grid_spec: tuple
    geometry: tuple | None
    exrhs: np.ndarray | None
    eps: float | None
    maxout: int | None
    ids: tuple = field(default=(1, 1))
    skipped: tuple = ()                    # what the deck asks for that was not computed (warnings)
    unsupported: tuple = ()                # why the project cannot solve this case (empty: it can)
    hertz_load: tuple | None = None        # (FN, PEN) that fixed a Hertzian grid and geometry (kept with D = 0)
    mater_params: tuple = ()               # the simplified theory's parameters (M = 2, 3)
    friction_rows: tuple = ()              # V = 3: (FSTAT, FKIN) per grid row (y index), () otherwise


def _soft(digits: dict, allowed: dict) -> list[str]:
    """Reasons for the digit values outside ``allowed`` (input still readable)."""
    out = []
    for letter, ok in allowed.items():
        v = digits.get(letter, 0)
        if v not in ok:
            out.append(f"control digit {letter} = {v} ({_MEANING.get((letter, v), 'this value')})")
    return out


def read_case(deck: Deck, state: Module3State, number: int, line: int, ids: tuple = (1, 1), *,
              ignore_subsurface: bool = False, ignore_temperature: bool = False) -> Module3Case:
    """Read the case that follows a ``3`` module line; update ``state``; return the resolved case.

    A digit value whose input this reader knows but whose physics the project does not have is
    recorded in the case's ``unsupported`` (and inherited by later cases that keep those data); an
    input it cannot read raises :class:`Unsupported`.  ``ignore_subsurface``: accept S = 1..3 and
    skip the subsurface stresses; ``ignore_temperature``: accept H = 1, 3 and skip the surface
    temperatures (outputs only; the case's ``skipped`` says so)."""
    digits = control_words(deck, "PBTNFS")
    hard = {"V": (0, 3), "L": (0, 1, 2, 3, 4, 6), "C": (0, 1, 2, 3, 4, 9), "M": (0, 1, 2, 3, 4, 5),
            "H": (0, 1, 3), "M2": (0, 1, 2), "E": (0, 1, 2, 3, 9), "G": (0, 1, 2, 3, 4, 5), "S": (0, 1, 2, 3),
            "T": (0, 1, 2, 3), "N": (0, 1), "F": (0, 1, 2), "D": (0, 1, 2), "Z": (0, 1, 2)}
    for reason in _soft(digits, hard):
        raise unsupported(deck.name, line, reason)
    own = _soft(digits, {"P": (0, 2, 3), "B": (0, 2, 3), "H": (0, 1, 3) if ignore_temperature else (0,),
                         "M2": (0,), "E": (0, 1, 9)})
    if digits["S"] and not ignore_subsurface:
        own.append(f"control digit S = {digits['S']} (subsurface stresses; --ignore-subsurface skips them)")
    inh = state.reasons
    T, C, M, L = digits["T"], digits["C"], digits["M"], digits["L"]
    maxout, eps, solver_notes = solver_parameters(deck, digits["G"], module=3, debug=digits["X"] == 1)
    kin = deck.reals(4, "PEN/FN CKSI/FXREL CETA/FYREL CPHI", optional=2)
    spin = (kin[4], kin[5]) if len(kin) >= 6 else (0.0, 0.0)
    if digits["V"] == 3:
        if L in (2, 3, 4, 6):
            inh["friction"] = f"control digit L = {L} ({_MEANING[('L', L)]})"
        elif L == 1 and not state.friction_rows and "friction" not in inh:
            raise InputError(f"{deck.name}, line {line}: V = 3 with L = 1 keeps friction per grid row; there is none")
    elif L == 0:
        state.friction = tuple(deck.reals(2, "FSTAT FKIN"))
        inh.pop("friction", None)
    elif L in (2, 3, 4, 6):
        deck.reals(4 if L == 6 else 5, "friction law parameters")
        deck.reals(2, "MEMDST MEM_S0")
        inh["friction"] = f"control digit L = {L} ({_MEANING[('L', L)]})"
    elif state.friction is None and "friction" not in inh:
        raise InputError(f"{deck.name}, line {line}: L = 1 keeps the friction of a previous case; there is none")
    if C >= 2:
        if T <= 1 and M == 5:
            deck.reals(1, "DT")
        if T > 1:
            r = deck.reals(3, "CHI DQ VELOC", angle=True)
            state.rolling = (r[0], r[1], r[2])
        if C == 4:
            ifm = deck.ints(3, "IF_METH VARIANT NN")
            deck.reals(2 * ifm[2], "Y(I), ALPHA(I)")
        if C == 9:
            state.cfname = deck.string("CFNAME")
        state.material = tuple(deck.reals(4, "POISS 1, 2  GG 1, 2"))
        state.mater_params = material_parameters(deck, digits["B"], M)
        state.inflcf = C
        for key, reason in (("inflcf", f"control digit C = {C} ({_MEANING.get(('C', C), '')})" if C in (3, 4) else None),
                            ("material", f"control digit M = {M} ({_MEANING.get(('M', M), '')})"
                             if M not in (0, 2, 3) else None)):
            if reason:
                inh[key] = reason
            else:
                inh.pop(key, None)
    elif state.material is None:
        raise InputError(f"{deck.name}, line {line}: C = {C} keeps the material of a previous case; there is none")
    damping_and_heat(deck, digits["M2"], digits["H"], M)
    if T > 1 and state.rolling is None:
        raise InputError(f"{deck.name}, line {line}: rolling (T = {T}) needs CHI, DQ, VELOC (C >= 2)")
    if digits["D"] == 2:
        ip = deck.ints(1, "IPOTCN")[0]
        state.hertz_load = (kin[0] if digits["N"] == 1 else None, kin[0] if digits["N"] == 0 else None)
        if ip in (-1, -2, -3, -4, -5):
            v = deck.reals(5, "MX MY A1/AA B1/AOB/BB SCALE")
            state.grid_spec = ("hertz", ip, int(v[0]), int(v[1]), tuple(v[2:]))
        elif ip == -6:
            v = deck.reals(6, "MX MY AA BNEG BPOS SCALE")
            state.grid_spec = ("hertz", ip, int(v[0]), int(v[1]), tuple(v[2:]))
        elif ip in (1, 2, 3, 4):
            v = deck.reals(6, "MX MY grid parameters")
            state.grid_spec = ("grid", ip, int(v[0]), int(v[1]), tuple(v[2:]))
        else:
            raise unsupported(deck.name, deck.line_number, f"IPOTCN = {ip} (unknown option)")
        if ip in (-4, -5, -6):
            inh["grid"] = f"IPOTCN = {ip} ({ {-4: '2D Hertzian rectangle', -5: '2D Hertzian rectangle', -6: 'SDEC'}[ip] })"
        else:
            inh.pop("grid", None)
    elif state.grid_spec is None:
        raise InputError(f"{deck.name}, line {line}: D = {digits['D']} keeps the grid of a previous case; there is none")
    mx, my = state.grid_spec[2], state.grid_spec[3]
    if digits["D"] == 2:      # the element count bounded before any array of the grid is read or allocated
        check_grid_memory(mx, my, "exact", f"{deck.name}, line {deck.lines[deck.pos - 1].number}: MX, MY",
                          "use a coarser grid")
    if digits["Z"] == 2 and state.grid_spec[1] > 0:
        ibase, iplan = deck.ints(2, "IBASE IPLAN")
        inh.pop("geometry", None)
        if ibase == 1:
            state.geometry = (1, tuple(deck.reals(6, "B1 .. B6")))
        elif ibase == 9:
            state.geometry = (9, np.array(deck.reals(mx * my, "H(I), I = 1 .. NPOT")))
        elif ibase == 2:
            nn = int(deck.reals(5, "NN XM RM Y1 DY1")[0])
            deck.reals(nn, "B(k), k = 1 .. NN")
            inh["geometry"] = "IBASE = 2 (body of revolution with a profile)"
        elif ibase == 3:
            deck.reals(8, "B1 .. B8")
            inh["geometry"] = "IBASE = 3 (quadratic plus sines)"
        else:
            raise unsupported(deck.name, deck.line_number, f"IBASE = {ibase} (unknown option)")
        if iplan == 2:
            deck.reals(6, "PL1 .. PL6")
        elif iplan == 3:
            deck.reals(8, "XL1 XH1 YL1 YH1 XL2 XH2 YL2 YH2")
        elif iplan == 4:
            npatch = deck.ints(1, "NPATCH")[0]
            deck.reals(4 * npatch, "XL XH YL YH per patch")
            if npatch > 1:
                deck.reals(npatch * (npatch - 1) // 2, "FAC(I, J)")
        elif iplan != 1:
            raise unsupported(deck.name, deck.line_number, f"IPLAN = {iplan} (unknown option)")
        if iplan != 1:
            inh["geometry"] = f"IPLAN = {iplan} (restricted planform)"
    if state.grid_spec[0] == "grid" and state.geometry is None and "geometry" not in inh:
        raise InputError(f"{deck.name}, line {line}: a non-Hertzian grid needs an undeformed distance (Z = 2)")
    if digits["V"] == 3 and L != 1:
        rows = tuple(tuple(deck.reals({0: 2, 6: 4}.get(L, 5), "friction parameters of one grid row"))
                     for _ in range(my))
        if L in (2, 3, 4, 6):
            deck.reals(2, "MEMDST MEM_S0")
        else:                                  # L = 0: (FSTAT, FKIN) per grid row
            state.friction_rows = rows
            state.friction = rows[0]
            inh.pop("friction", None)
    elif digits["V"] != 3:
        state.friction_rows = ()
    if digits["E"] == 9:
        state.exrhs = np.array(deck.reals(2 * mx * my, "EXRHS(I, 2:3), I = 1 .. NPOT")).reshape(mx * my, 2)
    elif digits["E"] == 0:
        state.exrhs = None
    elif digits["E"] == 1 and state.exrhs is None:
        raise InputError(f"{deck.name}, line {line}: E = 1 keeps the extra rigid slip of a previous case; there is none")
    skipped = solver_notes
    if digits["S"] >= 1:
        if digits["S"] >= 2:
            _skip_subsurface(deck, digits["S"])
        if ignore_subsurface:
            skipped = skipped + (f"subsurface stresses (S = {digits['S']}) not computed",)
    if digits["H"] and ignore_temperature:
        skipped = skipped + (f"surface temperatures (H = {digits['H']}) not computed",)
    state.case_count += 1
    N, F = digits["N"], digits["F"]
    return Module3Case(
        number=number, line=line, deck=deck.name, digits=digits,
        pen=kin[0] if N == 0 else None, fn=kin[0] if N == 1 else None,
        cksi=kin[1] if F == 0 else None, fxrel=kin[1] if F >= 1 else None,
        ceta=kin[2] if F <= 1 else None, fyrel=kin[2] if F == 2 else None,
        cphi=kin[3], spin_centre=spin, friction=state.friction, rolling=state.rolling,
        material=state.material, inflcf=state.inflcf, cfname=state.cfname, grid_spec=state.grid_spec,
        geometry=state.geometry, exrhs=state.exrhs, eps=eps, maxout=maxout, ids=ids, skipped=skipped,
        unsupported=tuple(own) + tuple(inh.values()), hertz_load=state.hertz_load,
        mater_params=state.mater_params, friction_rows=state.friction_rows)


def _skip_subsurface(deck: Deck, S: int) -> None:
    """Read past the subsurface input (user guide, "Subsurface-stress input in the file")."""
    deck.ints(2, "subsurface MATFIL OUTPUT")
    if S != 3:
        return
    for _ in range(10000):
        isubs = deck.ints(1, "ISUBS")[0]
        if isubs == 0:
            return
        if isubs in (2, 6):
            deck.ints(6, "IXL IXINC IXH IYL IYINC IYH")
        elif isubs in (3, 7):
            nx, ny = deck.ints(2, "NX NY")
            deck.ints(nx, "IX(i)")
            deck.ints(ny, "IY(j)")
        if isubs in (1, 2, 3):
            deck.reals(3, "NZ ZL DZ")
        elif isubs in (5, 6, 7):
            nz = deck.ints(1, "NZ")[0]
            deck.reals(nz, "Z(iz)")
        elif isubs == 9:
            nx, ny, nz = deck.ints(3, "NX NY NZ")
            deck.reals(nx, "X(i)")
            deck.reals(ny, "Y(j)")
            deck.reals(nz, "Z(k)")
        elif isubs not in (1, 2, 3, 5, 6, 7):
            raise deck.error("ISUBS", f"unknown block type {isubs}")
    raise deck.error("ISUBS", "more than 10000 blocks")


def grid_of(case: Module3Case):
    """(PlanarGrid, h) of a direct grid specification (IPOTCN > 0, user guide "Direct specification
    of the potential contact area", eq. x_i), h from IBASE (eq. quadr_ud, or the table in CONTACT's
    element order I = ix + (iy-1) mx)."""
    from conformal.grid import PlanarGrid

    kind, ip, mx, my, v = case.grid_spec
    if ip == 1:
        xl, yl, dx, dy = v
    elif ip == 2:
        xl, yl, xh, yh = v
        dx, dy = (xh - xl) / mx, (yh - yl) / my
    elif ip == 3:
        xc1, yc1, dx, dy = v
        xl, yl = xc1 - dx / 2, yc1 - dy / 2
    else:
        xc1, yc1, xcm, ycm = v
        if mx < 2 or my < 2:
            raise InputError(f"{case.deck}: IPOTCN = 4 needs MX, MY >= 2")
        dx, dy = (xcm - xc1) / (mx - 1), (ycm - yc1) / (my - 1)
        xl, yl = xc1 - dx / 2, yc1 - dy / 2
    grid = PlanarGrid(mx, my, dx, dy, xl, yl)
    ibase, g = case.geometry
    if ibase == 1:
        b1, b2, b3, b4, b5, b6 = g
        X, Y = grid.mesh()
        h = b1 * X**2 + b2 * X * Y + b3 * Y**2 + b4 * X + b5 * Y + b6
    else:
        h = np.asarray(g, dtype=float).reshape(my, mx).T.copy()
    return grid, h


def exrhs_grid(case: Module3Case) -> np.ndarray | None:
    """The extra rigid slip (2, mx, my) in CONTACT's element order, or None."""
    if case.exrhs is None:
        return None
    mx, my = case.grid_spec[2], case.grid_spec[3]
    e = case.exrhs.reshape(my, mx, 2)
    return np.stack([e[:, :, 0].T, e[:, :, 1].T])


def chi_direction(case: Module3Case) -> int:
    """+1 for rolling along +x (CHI = 0), -1 along -x (CHI = 180 degrees); others refused."""
    chi = case.rolling[0] if case.rolling else 0.0
    if abs(math.remainder(chi, 2 * math.pi)) < 1e-9:
        return 1
    if abs(abs(math.remainder(chi, 2 * math.pi)) - math.pi) < 1e-9:
        return -1
    raise unsupported(case.deck, case.line, f"rolling direction CHI = {chi:g} rad (only 0 and 180 degrees)")
