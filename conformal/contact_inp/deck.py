"""A whole CONTACT input deck: its modules and cases, solved in order.

A deck is a series of module calls (user guide, "Specification of the input file"): ``3 {REID,
CPID}`` starts a module-3 case, ``1 {REID}`` a module-1 (wheel-rail) case (conformal.contact_inp.
module1, solved as a wheel-rail scene by conformal.contact_inp.solve1), ``0`` ends the run.
Later cases inherit the data of earlier ones (one :class:`~conformal.contact_inp.module3.Module3State`
per result element and contact problem).  Cases in a sequence (user guide "Multiple cases,
sequences": P = 0 or 3 with a shift or transient rolling, T = 1, 2) continue from the tractions of
the previous case: they are solved together as one load history (conformal.solvers.history);
every other case stands alone.  A case with R = 2 or 3 is read (its data are kept) but not solved,
as in CONTACT.  After a case with R = 0 or 2 the next case follows without a module line (user
guide, the R digit: "stay in the same module").
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from conformal.contact_inp.module3 import Module3Case, Module3State, read_case, unsupported
from conformal.contact_inp.tokens import Deck
from conformal.errors import InputError


@dataclass(frozen=True, eq=False)
class ParsedDeck:
    path: Path
    cases: tuple            # Module3Case, in the order of the deck


def read_deck(path, *, ignore_subsurface: bool = False, ignore_temperature: bool = False) -> ParsedDeck:
    """Read every case of a deck (InputError / Unsupported naming the line and digit);
    ``ignore_subsurface`` / ``ignore_temperature``: accept S = 1..3 / H = 1, 3 and skip those
    outputs (each case's warnings say so)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"inp: no such file: {path}")
    text = path.read_text(encoding="latin-1")
    deck = Deck(path.name, text)
    states: dict = {}
    cases: list = []
    number = 0
    head = None                       # the module call in force: R = 0, 2 stay in the module
    for _ in range(1_000_000):
        if deck.at_end:
            break
        line = deck.line_number
        if head is None:
            head = deck.ints(1, "MODULE", optional=2)
        module = head[0]
        if module == 0:
            break
        if module not in (1, 3):
            raise unsupported(deck.name, line, f"module {module}")
        number += 1
        opts = dict(ignore_subsurface=ignore_subsurface, ignore_temperature=ignore_temperature)
        if module == 1:
            from conformal.contact_inp.module1 import Module1State, read_case as read_case1

            state1 = states.setdefault(("module 1", head[1] if len(head) > 1 else 1), Module1State())
            case = read_case1(deck, state1, number, line, **opts)
        else:
            ids = (head[1] if len(head) > 1 else 1, head[2] if len(head) > 2 else 1)
            case = read_case(deck, states.setdefault(ids, Module3State()), number, line, ids, **opts)
        cases.append(case)
        if case.digits["R"] in (1, 3):   # return to the main program: the next case names its module
            head = None
    if not cases:      # an empty deck (or only comments / "0 MODULE"): `inp` reported success for nothing
        raise InputError(f"{path.name}: no cases (a CONTACT deck starts with a module number, e.g. ' 3  MODULE')")
    return ParsedDeck(path=path, cases=tuple(cases))


def _chains(cases) -> list[list[Module3Case]]:
    """Cases that are solved (R = 0, 1) grouped into independent cases and sequences."""
    chains: list[list[Module3Case]] = []
    prev_T = None
    for c in cases:
        if getattr(c, "module", 3) == 1:        # wheel-rail cases stand alone (steady rolling only)
            if c.digits["R"] in (0, 1):
                chains.append([c])
            prev_T = None
            continue
        T, P = c.digits["T"], c.digits["P"]
        solved = c.digits["R"] in (0, 1)
        continues = T in (1, 2) and P in (0, 3) and bool(chains) and prev_T is not None
        if continues and prev_T == 0:
            c = replace(c, unsupported=c.unsupported + ("a shift or transient case continuing from a frictionless "
                                                        "case",))
        if continues and chains[-1][-1].ids == c.ids:
            if solved:
                chains[-1].append(c)
        elif solved:
            chains.append([c])
        prev_T = T if solved else prev_T
    return chains


@dataclass(frozen=True, eq=False)
class Plan:
    """What will be solved: chains of cases with their problems; ``unsupported`` the (case, reason)
    of every case that cannot be solved (a case continuing an unsupported one included)."""

    chains: tuple
    unsupported: tuple


def plan(parsed: ParsedDeck) -> Plan:
    """Map every case onto the project's problems; collect the reasons for the others."""
    from conformal.contact_inp.solve1 import scene_of
    from conformal.contact_inp.module3 import Unsupported

    base = parsed.path.parent
    chains, bad = [], []
    heights: dict = {}                    # first-touch heights of N = 0 cases, by geometry
    for chain in _chains(parsed.cases):
        items = []
        broken = None                     # the first unsupported case of this chain
        for k, c in enumerate(chain):
            if broken is not None:
                bad.append((c, f"continues unsupported case {broken}"))
                continue
            reason = c.unsupported[0] if c.unsupported else None
            prob = None
            if reason is None:
                try:
                    if getattr(c, "module", 3) == 1:
                        prob = scene_of(c, base, memo=heights)
                        _check_profiles(prob, base)
                    else:     # module 3 only: its solver path (conformal.contact_inp.solve3) loads here
                        from conformal.contact_inp.solve3 import problem_of

                        prob = problem_of(c, base)
                except Unsupported as exc:
                    reason = str(exc).split("not supported: ", 1)[-1]
                except InputError as exc:     # e.g. nu = 0.5, which the project's materials refuse
                    reason = str(exc)
            if reason is None and k > 0:      # a module-3 sequence (module-1 chains have one case)
                from conformal.contact_inp.solve3 import same_geometry

                p0 = items[0][1]
                if p0.info or prob.info or p0.kinematics.direction != 1 or not same_geometry(p0, prob):
                    reason = ("a sequence (P = 0) whose grid, material or friction changes, or with C = 9, E = 9 "
                              "or CHI = 180 degrees, or friction per grid row V = 3")
            if reason is not None:
                bad.append((c, reason))
                broken = c.number
                continue
            items.append((c, prob))
        if items:
            chains.append(tuple(items))
    return Plan(chains=tuple(chains), unsupported=tuple(bad))


def _check_profiles(raw: dict, base: Path) -> None:
    """Read and fit a module-1 case's profiles (smoothing included) so that a profile the project
    refuses (e.g. smoothing that moves it more than 0.1 mm) refuses the case before any solve."""
    from conformal.geometry.wheelrail import profile_curves
    from conformal.scene import scene_from_dict

    profile_curves(scene_from_dict(raw, base_dir=base).geometry, base)


def solve_deck(parsed: ParsedDeck, cases=None):
    """Yield one JSON-ready dict per solved case, in the order of the deck; ``cases``: only these
    case numbers (a case of a sequence is solved with the cases before it).  Unsupported cases
    among those asked for raise :class:`~conformal.contact_inp.module3.Unsupported` before anything
    is solved.

    Consecutive module-1 cases of one sequence of wheelset positions (the same
    :func:`~conformal.contact_inp.solve1.sequence_key`: profiles, track, grid, material, friction,
    load and model) start each from the one solved before it, as CONTACT does and as a sweep and
    the Manchester study do (:class:`~conformal.cases.wheelrail.WarmStart`); a case is then the
    same vertical balance to its tolerances as solved alone, not bitwise (module 1 of
    conformal.contact_inp.solve1).  The module-3 solver path (conformal.contact_inp.solve3, history)
    loads only for a deck with module-3 cases."""
    from conformal.contact_inp.module3 import Unsupported

    pl = plan(parsed)
    want = None if cases is None else set(int(c) for c in cases)
    if want is not None:
        known = {c.number for c in parsed.cases}
        missing = sorted(want - known)
        if missing:
            raise InputError(f"--cases: the deck has cases 1 .. {len(known)}, not {missing}")
    for c, reason in pl.unsupported:
        if want is None or c.number in want:
            raise Unsupported(f"{c.deck}, line {c.line} (case {c.number}): not supported: {reason}")
    warm, warm_key = None, None           # the last module-1 case's warm start and its sequence
    for chain in pl.chains:
        if want is not None:
            keep = [k for k, (c, _) in enumerate(chain) if c.number in want]
            if not keep:
                continue
            chain = chain[:keep[-1] + 1]
        first, p0 = chain[0]
        if getattr(first, "module", 3) == 1:
            from conformal.cases.wheelrail import WarmStart
            from conformal.contact_inp.solve1 import sequence_key, solve_case, summary as summary1

            key = sequence_key(p0)
            if key is None or key != warm_key:
                warm = None
            r = solve_case(first, p0, parsed.path.parent, warm=warm)
            warm, warm_key = (None, None) if key is None else (WarmStart.from_result(r, warm), key)
            yield summary1(first, r)
            continue
        from conformal.contact_inp.solve3 import history_step, summary
        from conformal.models import solve_problem
        from conformal.solvers.history import solve_history

        T0 = first.digits["T"]
        if len(chain) == 1 and (T0 in (0, 3) or (T0 == 1 and first.digits["P"] == 2)):
            yield summary(first, solve_problem(p0))
            continue
        steps = [history_step(c) for c, _ in chain]
        if first.digits["T"] == 3:
            steps[0] = replace(steps[0], rolling="steady")
        hs = [p.h for _, p in chain]
        hist = solve_history(p0, steps, undeformed=None if all(h is hs[0] for h in hs) else hs)
        for (c, _), r in zip(chain, hist.steps):
            if want is None or c.number in want:
                yield summary(c, r)


def deck_scene(path, number: int, **model) -> dict:
    """The scene dict of case ``number`` of a module-1 deck (profiles beside it), with ``[model]``
    keys replaced by ``model`` (e.g. ``influence="halfspace"`` to compare the project's own model
    on CONTACT's case)."""
    from conformal.contact_inp.solve1 import scene_of

    path = Path(path)
    cases = {c.number: c for c in read_deck(path).cases}
    if number not in cases or getattr(cases[number], "module", 3) != 1:
        raise unsupported(path.name, 0, f"case {number} is not a module-1 case of the deck")
    raw = scene_of(cases[number], path.parent)
    raw["model"] = {**raw["model"], **model}
    return raw
