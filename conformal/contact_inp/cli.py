"""``conformal inp FILE.inp [--out DIR]``: solve the cases of a CONTACT input deck.

Prints one JSON object per solved case (JSON Lines) to stdout; ``--out DIR`` also writes
``DIR/<stem>.jsonl`` (atomically, after the last case).  A digit or feature the reader does not
support ends the run with one error line naming it (exit 2, conformal.cli).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path


def add_parsers(sub) -> None:
    """Add the ``inp`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser("inp", help="solve the cases of a CONTACT input deck (.inp): JSON Lines")
    p.add_argument("deck", help="CONTACT input file (.inp): module-3 and module-1 (wheel-rail) cases")
    p.add_argument("--out", metavar="DIR", help="also write DIR/<stem>.jsonl")
    p.add_argument("--cases", metavar="N,M,...", help="solve only these case numbers (sequences from their start)")
    p.add_argument("--ignore-subsurface", action="store_true",
                   help="accept S = 1..3 and skip the subsurface stresses (each case warns)")
    p.add_argument("--ignore-temperature", action="store_true",
                   help="accept H = 1, 3 and skip the surface temperatures (each case warns)")
    p.add_argument("--allow-unconverged", action="store_true",
                   help="exit 0 also when a case did not converge (default: exit status 3)")
    p.set_defaults(func=cmd_inp)


def _case_numbers(text: str | None):
    from conformal.errors import InputError

    if text is None:
        return None
    try:
        nums = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"--cases: whole numbers separated by commas, got {text!r}") from None
    if not nums or min(nums) < 1:
        raise InputError(f"--cases: case numbers >= 1, got {text!r}")
    return nums


def cmd_inp(args) -> int:
    from conformal._threads import single_threaded_blas
    from conformal.contact_inp.combine import PREFIX
    from conformal.contact_inp.deck import read_deck, solve_deck
    from conformal.errors import InputError, unconverged_exit
    from conformal.files import check_output_path, write_text

    cases = _case_numbers(args.cases)
    out_path = None
    if args.out is not None:
        folder = Path(args.out)
        if folder.exists() and not folder.is_dir():
            raise InputError(f"--out: {folder} is a file, not a folder")
        out_path = folder / (Path(args.deck).stem + ".jsonl")
        check_output_path(str(out_path), "--out")           # before the cases are solved, not after
    parsed = read_deck(args.deck, ignore_subsurface=args.ignore_subsurface,
                       ignore_temperature=args.ignore_temperature)
    lines, unconverged = [], []
    with single_threaded_blas():          # once for the deck, not once per case (conformal._threads)
        for d in solve_deck(parsed, cases=cases):
            if d.get("converged") is False:
                unconverged.append(str(d.get("case")))
            text = json.dumps(d)
            print(text, flush=True)
            for w in d.get("warnings", []):      # CONTACT's patch combination not reproduced: one line each
                if w.startswith(PREFIX):
                    print(f"case {d['case']}: {w}", file=sys.stderr)
            lines.append(text)
    if out_path is not None:      # conformal.files: atomic, like every file the package writes
        write_text(out_path, "".join(t + "\n" for t in lines))
        print(f"wrote {out_path}", file=sys.stderr)
    if unconverged:
        return unconverged_exit(f"case{'s' if len(unconverged) > 1 else ''} {', '.join(unconverged)}",
                                args.allow_unconverged)
    return 0
