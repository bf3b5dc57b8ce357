"""``conformal table build|refine|info``: the command-line side of :mod:`conformal.tables`.

    conformal table build SPEC.toml --out TABLE.npz [--workers N] [--scheduler ADDRESS|local]
    conformal table refine TABLE.npz --out OUT.npz --box T0:T1,S0:S1,TH0:TH1 --q=QLO:QHI [--workers N]
    conformal table info [TABLE.npz]

``refine`` adds the midpoints of the q cells in [QLO, QHI] as extra nodes for every node of the
box (half-open index ranges along ln a/b, s, theta; every nu): a targeted refinement
(:func:`conformal.tables.build.add_patch`), resumable like ``build``; ``default`` names the
shipped table.
"""
from __future__ import annotations

import json
import sys


def add_parsers(sub) -> None:
    """Add the ``table`` command (with ``build`` and ``info``) to the subparsers of ``conformal``."""
    t = sub.add_parser("table", help="creep-force tables from the exact theory: build, info")
    tsub = t.add_subparsers(dest="table_command", required=True)
    b = tsub.add_parser("build", help="build (or resume) a creep-force table: one exact solve per node")
    b.add_argument("spec", help="SPEC.toml: [table] ranges and node counts, [solver] grid_n, tol, [build] chunk")
    b.add_argument("--out", required=True, metavar="TABLE.npz", help="the table file to write")
    b.add_argument("--workers", type=int, default=1, help="parallel workers (local processes or LocalCluster)")
    b.add_argument("--scheduler", metavar="ADDRESS",
                   help="Dask scheduler address (tcp://host:8786), or 'local' for a Dask LocalCluster")
    b.add_argument("--no-progress", action="store_true", help="no progress bar")
    b.add_argument("--allow-unconverged", action="store_true",
                   help="exit 0 also when some nodes did not converge (default: exit status 3)")
    b.set_defaults(func=cmd_build)
    r = tsub.add_parser("refine", help="add extra q nodes (cell midpoints) in a box of a built table")
    r.add_argument("table", help="TABLE.npz ('default': the table shipped with the package)")
    r.add_argument("--out", required=True, metavar="OUT.npz", help="the refined table file to write")
    r.add_argument("--box", required=True, metavar="T0:T1,S0:S1,TH0:TH1",
                   help="node index ranges (half-open) along ln a/b, s, theta")
    r.add_argument("--q", required=True, metavar="QLO:QHI", help="add the q cell midpoints in [QLO, QHI] (write --q=QLO:QHI when QLO < 0)")
    r.add_argument("--workers", type=int, default=1, help="parallel workers (local processes or LocalCluster)")
    r.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler address, or 'local'")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.add_argument("--allow-unconverged", action="store_true",
                   help="exit 0 also when some nodes did not converge (default: exit status 3)")
    r.set_defaults(func=cmd_refine)
    i = tsub.add_parser("info", help="print a table's metadata (default: the shipped table)")
    i.add_argument("table", nargs="?", default=None, help="TABLE.npz (default: the table shipped with the package)")
    i.set_defaults(func=cmd_info)


def cmd_build(args) -> int:
    from conformal.files import check_output_path
    from conformal.tables.build import build_table
    from conformal.tables.spec import load_spec

    spec = load_spec(args.spec)
    check_output_path(args.out, "--out", (".npz",))        # before the build, not after it
    rep = build_table(spec, args.out, workers=args.workers, scheduler=args.scheduler,
                      progress=not args.no_progress)
    for label, why in rep.failed:
        print(f"conformal: {label}: failed: {why}", file=sys.stderr)
    print(rep.summary())
    return _exit_code(rep, args.allow_unconverged)


def _exit_code(rep, allow_unconverged: bool) -> int:
    """1 when chunks failed (the table is not written; rerun to resume), 3 when the table was
    written with nodes that did not converge (its metadata counts them), unless allowed."""
    if rep.failed:
        return 1
    if rep.nonconverged:
        from conformal.errors import unconverged_exit

        return unconverged_exit(f"the exact solve of {rep.nonconverged} table nodes", allow_unconverged,
                                where="\"nonconverged_nodes\" in the table's metadata; table info shows it")
    return 0


def _ranges(text: str, n: int, what: str) -> list[float]:
    from conformal.errors import InputError

    try:
        parts = [p.split(":") for p in text.split(",")]
        if len(parts) != n or any(len(p) != 2 for p in parts):
            raise ValueError
        return [float(v) for p in parts for v in p]
    except ValueError:
        raise InputError(f"--{what}: expected {','.join(['LO:HI'] * n)}, got {text!r}") from None


def cmd_refine(args) -> int:
    from conformal.errors import InputError
    from conformal.files import check_output_path
    from conformal.tables.build import add_patch, midpoints
    from conformal.tables.table import load_table

    box = _ranges(args.box, 3, "box")
    if any(v != int(v) for v in box):
        raise InputError(f"--box: node indices must be integers, got {args.box!r}")
    q_lo, q_hi = _ranges(args.q, 1, "q")
    q = midpoints(load_table(args.table).spec, q_lo, q_hi)
    if q.size == 0:
        raise InputError(f"--q: no q cell midpoint in [{q_lo:g}, {q_hi:g}]")
    check_output_path(args.out, "--out", (".npz",))
    rep = add_patch(args.table, tuple(int(v) for v in box), q, args.out, workers=args.workers,
                    scheduler=args.scheduler, progress=not args.no_progress)
    for label, why in rep.failed:
        print(f"conformal: {label}: failed: {why}", file=sys.stderr)
    print(rep.summary())
    return _exit_code(rep, args.allow_unconverged)


def cmd_info(args) -> int:
    from conformal.tables.table import load_table

    print(json.dumps(load_table(args.table).info(), indent=2))
    return 0
