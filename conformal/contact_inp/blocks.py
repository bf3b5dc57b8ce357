"""Input blocks that modules 1 and 3 of a CONTACT deck share (user guide, "Specification of the
input file": the control words, the solver parameters of digit G, the material parameters of
digits B and M, damping M2 = 2 and temperature H = 3).

>>> from conformal.contact_inp.tokens import Deck
>>> d = Deck("x.inp", " 203100\\n 022020 2\\n 0001341\\n 100 100 30 1 1e-8\\n")
>>> digits = control_words(d, "PBTNFS")
>>> digits["T"], digits["L"], digits["V"], digits["M2"], digits["O"], solver_parameters(d, digits["G"], module=3)
(3, 0, 0, 2, 3, (1, 1e-08))
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


def solver_parameters(deck: Deck, G: int, *, module: int, debug: bool = False) -> tuple[int | None, float | None]:
    """The debug digits (X = 1: ``debug``) and the solver block of digit G; returns (MAXOUT, EPS),
    None for what the case does not give.  The MAXGS line: module 1 for G != 1 (with the optional
    NPOT_MAX), module 3 for G = 0, 2, 3, 4 (the user guide's two input summaries differ in G = 5)."""
    if debug:
        deck.ints(1, "PSFLCIN debug digits", optional=1)
    maxout = eps = None
    if (G != 1) if module == 1 else G in (0, 2, 3, 4):
        g = deck.reals(5, "MAXGS MAXIN MAXNR MAXOUT EPS", optional=1 if module == 1 else 0, angle=True)
        maxout, eps = int(g[3]), g[4]
    if G in (2, 3):
        deck.reals(4, "OMEGAH OMEGAS INISLP OMGSLP", angle=True)
    elif G == 4:
        deck.reals(2, "INISLP OMGSLP", angle=True)
    elif G == 5:
        deck.reals(8, "FDECAY BETATH KDOWFB D_IFC D_LIN D_CNS D_SLP POW_S", angle=True)
    return maxout, eps


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
