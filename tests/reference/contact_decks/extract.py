"""Rebuild this folder from a CONTACT checkout (github.com/eve70a/CONTACT, Apache-2.0).

    PYTHONPATH=. python tests/reference/contact_decks/extract.py /path/to/CONTACT [DECK.inp ...]

(names after the checkout: redo only those decks; the others keep their manifest entries).
Cases with friction varying over the profile (module 1, V = 1) are solved, since whether the
friction is constant over every conformal strip (D = 4), and whether the wheel-rail set-up can
place the case, is known only then (about 6 minutes, testbank case 35).  Module-1 cases where
CONTACT's rule for contact regions (D_COMB, D_SEP, D_TURN) differs from the reader's patches
(conformal.contact_inp.combine, at the height of the normal balance; the warnings of the full
solve for the ``t3_*`` decks) are listed per deck under
``patch_combination``: they run, with a warning, and are not counted as agreeing with CONTACT.

For every public deck (examples/*.inp, testbank/**/*.inp) it counts the cases (the ``Case``
blocks of its .ref_out) and the cases ``conformal inp`` can solve, with the reasons for the
others, into manifest.json; decks with at least one supported case are copied with their
.ref_out reduced to the totals of each case (the lines that conformal.contact_inp.refout reads).
"""
from __future__ import annotations

import json
import re
import shutil
import sys
from pathlib import Path

from conformal.contact_inp.deck import plan, read_deck, solve_deck
from conformal.contact_inp.module3 import Unsupported
from conformal.errors import InputError

HERE = Path(__file__).resolve().parent


#: header lines whose next line holds the values the tests read
_HEADERS = ("FN ", "FN/G", "NPOT", "FX(TR)", "XCP(TR)", "VX_WS", "BAR_FN", "TILDE_FN")


def trimmed_ref_out(text: str) -> str:
    """The case headers and totals blocks of a .ref_out (module 3: totals; module 1: also the
    forces on the rail, the patch separators and each patch's reference location)."""
    keep, lines = [], text.splitlines()
    for i, ln in enumerate(lines):
        s = ln.strip()
        if re.match(r"^Case +\d+$", s) or "DATA FOR CONTACT PATCH" in s or s == "TOTAL FORCES ON RAIL":
            keep.append(ln)
        elif s.startswith(_HEADERS) and (not s.startswith("FN ") or " FX " in s):
            keep.extend(lines[i:i + 2])
    return "\n".join(keep) + "\n"


#: decks whose module-1 cases are solved for the patch-combination check (one case each, 1-2 minutes):
#: their full solve ends a few micrometres from the normal balance, where the tread region splits in two
SOLVED = {"t3_t1_conformal.inp", "t3_t2_conformal.inp", "t3_t1_force.inp", "t3_t2_force.inp"}


def _combination(case, raw: dict, base_dir: Path) -> bool:
    """Whether CONTACT combines, blends or turns the contact regions of a module-1 case differently
    from the reader's patches (conformal.contact_inp.combine): at the height of the normal balance,
    or from the warnings of the full solve for the decks in SOLVED."""
    from conformal.contact_inp.combine import PREFIX, loaded_warnings
    from conformal.contact_inp.solve1 import solve_case, summary, thresholds
    from conformal.errors import ConvergenceError, NoContactError
    from conformal.scene import scene_from_dict

    if getattr(case, "module", 3) != 1:
        return False
    try:
        if Path(case.deck).name in SOLVED:
            return any(w.startswith(PREFIX) for w in summary(case, solve_case(case, raw, base_dir))["warnings"])
        return bool(loaded_warnings(scene_from_dict(raw, base_dir=base_dir, name=raw["name"]), *thresholds(case)))
    except (InputError, NoContactError, ConvergenceError):
        return False


def main(root: str, only=()) -> int:
    """``only``: deck file names to redo; the others keep their manifest entries."""
    root = Path(root)
    decks = sorted(root.glob("examples/*.inp")) + sorted(root.glob("testbank/**/*.inp"))
    manifest = []
    for inp in decks:
        if only and inp.name not in only:
            old = {e["deck"]: e for e in json.loads((HERE / "manifest.json").read_text(encoding="utf-8"))["decks"]}
            if inp.relative_to(root).as_posix() in old:
                manifest.append(old[inp.relative_to(root).as_posix()])
                continue
        rel = inp.relative_to(root).as_posix()
        ref = inp.with_suffix(".ref_out")
        if not ref.is_file():
            continue
        n_cases = len(re.findall(r"^ Case +\d+\s*$", ref.read_text(encoding="latin-1"), flags=re.M))
        entry = {"deck": rel, "cases": n_cases, "supported": 0, "reasons": {}}
        try:
            parsed = read_deck(inp, ignore_subsurface=True, ignore_temperature=True)
            pl = plan(parsed)
            entry["supported"] = sum(len(ch) for ch in pl.chains)
            entry["module"] = sorted({getattr(c, "module", 3) for c in parsed.cases})
            for _, why in pl.unsupported:
                entry["reasons"][why] = entry["reasons"].get(why, 0) + 1
            for case, _ in (item for chain in pl.chains for item in chain):
                if getattr(case, "friction_table", ()):   # V = 1: checked over the patches after the solve
                    try:
                        list(solve_deck(parsed, cases=[case.number]))
                    except Unsupported as exc:
                        why = str(exc).split("not supported: ", 1)[-1]
                        entry["reasons"][why] = entry["reasons"].get(why, 0) + 1
                        entry["supported"] -= 1
                        entry.setdefault("refused_after_solve", []).append(case.number)
            comb = [case.number for case, raw in (item for chain in pl.chains for item in chain)
                    if case.number not in entry.get("refused_after_solve", []) and _combination(case, raw, inp.parent)]
            if comb:
                entry["patch_combination"] = comb
        except InputError as exc:
            entry["reasons"][str(exc).split(": ", 1)[-1]] = n_cases
        manifest.append(entry)
        if entry["supported"]:
            shutil.copyfile(inp, HERE / inp.name)
            for case, _ in (item for chain in pl.chains for item in chain):
                for name in (getattr(case, "rail_file", None), getattr(case, "wheel_file", None)):
                    if name:          # the profiles of the supported wheel-rail cases, beside the deck
                        shutil.copyfile(inp.parent / name, HERE / Path(name).name)
            (HERE / ref.name).write_text(trimmed_ref_out(ref.read_text(encoding="latin-1")), encoding="utf-8")
        print(f"{rel}: {entry['supported']} / {n_cases}")
    total = sum(e["cases"] for e in manifest)
    ok = sum(e["supported"] for e in manifest)
    out = {"source": "github.com/eve70a/CONTACT (Apache-2.0), E.A.H. Vollebregt / Vtech CMCC",
           "cases": total, "supported": ok,
           "patch_combination": sum(len(e.get("patch_combination", [])) for e in manifest), "decks": manifest}
    (HERE / "manifest.json").write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    print(f"{ok} of {total} cases ({100.0 * ok / total:.1f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], set(sys.argv[2:])))
