"""``conformal inp FILE.inp [--out DIR]``: solve the cases of a CONTACT input deck.

Prints one JSON object per solved case (JSON Lines) to stdout; ``--out DIR`` also writes
``DIR/<stem>.jsonl`` (atomically, after the last case).  A digit or feature the reader does not
support ends the run with one error line naming it (exit 2, conformal.cli).
"""
from __future__ import annotations

import json
import os
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
    from conformal.contact_inp.combine import PREFIX
    from conformal.contact_inp.deck import read_deck, solve_deck
    from conformal.errors import InputError

    cases = _case_numbers(args.cases)
    out_path = None
    if args.out is not None:
        folder = Path(args.out)
        if folder.exists() and not folder.is_dir():
            raise InputError(f"--out: {folder} is a file, not a folder")
        out_path = folder / (Path(args.deck).stem + ".jsonl")
    parsed = read_deck(args.deck, ignore_subsurface=args.ignore_subsurface,
                       ignore_temperature=args.ignore_temperature)
    lines = []
    for d in solve_deck(parsed, cases=cases):
        text = json.dumps(d)
        print(text, flush=True)
        for w in d.get("warnings", []):      # CONTACT's patch combination not reproduced: one line each
            if w.startswith(PREFIX):
                print(f"case {d['case']}: {w}", file=sys.stderr)
        lines.append(text)
    if out_path is not None:
        out_path.parent.mkdir(parents=True, exist_ok=True)
        tmp = out_path.with_name(f".{out_path.name}.{os.getpid()}.tmp")
        tmp.write_text("".join(t + "\n" for t in lines), encoding="utf-8")
        os.replace(tmp, out_path)
        print(f"wrote {out_path}", file=sys.stderr)
    return 0
