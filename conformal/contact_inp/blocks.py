"""Input blocks that modules 1 and 3 of a CONTACT deck share (user guide, "Specification of the
input file": the control words, the solver parameters of digit G, the material parameters of
digits B and M, damping M2 = 2 and temperature H = 3).

>>> from conformal.contact_inp.tokens import Deck
>>> d = Deck("x.inp", " 203100\\n 022020 2\\n 0001341\\n 100 100 30 1 1e-8\\n")
>>> digits = control_words(d, "PBTNFS")
>>> maxout, eps, notes = solver_parameters(d, digits["G"], module=3)
>>> digits["T"], digits["L"], digits["V"], digits["M2"], digits["O"], maxout, eps, notes[0][:11]
(3, 0, 0, 2, 3, 1, 1e-08, 'MAXGS = 100')
"""
from __future__ import annotations

from conformal.contact_inp.tokens import Deck

#: number of material-model parameters per digit M (user guide, "Material parameters")
MATERIAL_PARAMETERS = {1: 4, 2: 4, 3: 3, 4: 4, 5: 3}


def control_words(deck: Deck, first: str) -> dict:
    """The three control words: ``first`` (module 3 PBTNFS, module 1 CPBTNFS: its CONFIG digit is
    returned as C1, C being INFLCF of the second word), VLDCMZE with the optional single digit M2
    after it (0 when absent; V = 0 for a six-digit word), XHGIAOWR."""
    d1 = deck.digits(first)
    if "C" in d1:
        d1["C1"] = d1.pop("C")
    d2 = deck.digits("VLDCMZE")
    ln2 = deck.lines[deck.pos - 1]
    d2["M2"] = int(ln2.tokens[1]) if len(ln2.tokens) > 1 and ln2.tokens[1].isdigit() and len(ln2.tokens[1]) == 1 else 0
    d3 = deck.digits("XHGIAOWR")
    return {**d1, **d2, **d3}


#: the iteration limit and default tolerance of the solvers a deck's case runs with (ModelSpec's defaults)
SOLVER_MAXIT, SOLVER_TOL = 1000, 1e-6


def eps_tolerance(eps: float | None) -> float:
    """The relative tolerance a module-3 case is solved with for the deck's EPS: EPS within
    [1e-10, 1e-6] (1e-8 without EPS; a zero or negative EPS gives 1e-10)."""
    return 1e-8 if eps is None else min(max(eps, 1e-10), SOLVER_TOL)


def solver_parameters(deck: Deck, G: int, *, module: int, debug: bool = False
                      ) -> tuple[int | None, float | None, tuple[str, ...]]:
    """The debug digits (X = 1: ``debug``) and the solver block of digit G; returns (MAXOUT, EPS,
    warnings), None for what the case does not give.  The MAXGS line: module 1 for G != 1 (with the optional
    NPOT_MAX), module 3 for G = 0, 2, 3, 4 (the user guide's two input summaries differ in G = 5).
    The warnings name what the deck gives and the solvers here do not use: MAXGS (CONTACT's
    Gauss-Seidel limit; the solvers stop at maxit = 1000), a zero or negative EPS (module 3: the
    tolerance used instead), EPS in module 1 (solved with tol = 1e-6)."""
    if debug:
        deck.ints(1, "PSFLCIN debug digits", optional=1)
    maxout = eps = None
    notes: list[str] = []
    if (G != 1) if module == 1 else G in (0, 2, 3, 4):
        g = deck.reals(5, "MAXGS MAXIN MAXNR MAXOUT EPS", optional=1 if module == 1 else 0, angle=True)
        maxout, eps = int(g[3]), g[4]
        notes.append(f"MAXGS = {g[0]:g} (CONTACT's Gauss-Seidel iteration limit) is not used: the solver here "
                     f"stops at its own limit, maxit = {SOLVER_MAXIT}")
        if module == 1:
            notes.append(f"EPS = {eps:g} is not used: module-1 cases are solved with tol = {SOLVER_TOL:g}")
        elif eps <= 0.0:
            notes.append(f"EPS = {eps:g} is not a tolerance (must be > 0): the solver uses tol = "
                         f"{eps_tolerance(eps):g}")
    if G in (2, 3):
        deck.reals(4, "OMEGAH OMEGAS INISLP OMGSLP", angle=True)
    elif G == 4:
        deck.reals(2, "INISLP OMGSLP", angle=True)
    elif G == 5:
        deck.reals(8, "FDECAY BETATH KDOWFB D_IFC D_LIN D_CNS D_SLP POW_S", angle=True)
    return maxout, eps, tuple(notes)


def material_parameters(deck: Deck, B: int, M: int) -> tuple:
    """After POISS and GG: FLXZ for B = 1 and the parameters of material model M (returned)."""
    if B == 1:
        deck.reals(1, "FLXZ", angle=True)
    n = MATERIAL_PARAMETERS.get(M, 0)
    return tuple(deck.reals(n, "material model parameters", angle=True)) if n else ()


def damping_and_heat(deck: Deck, M2: int, H: int, M: int) -> None:
    """Read past the damping (M2 = 2) and temperature (H = 3) blocks."""
    if M2 == 2:
        deck.reals(4, "CDAMPN CDAMPT DFNMAX DFTMAX", angle=True)
    if H == 3:
        deck.reals(8, "BKTEMP HEATCP LAMBDA DENS (bodies 1, 2)", angle=True)
        if M == 4:
            deck.reals(1, "BETAPL", angle=True)
