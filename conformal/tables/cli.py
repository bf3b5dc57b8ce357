"""``conformal table build|info``: the command-line side of :mod:`conformal.tables`.

    conformal table build SPEC.toml --out TABLE.npz [--workers N] [--scheduler ADDRESS|local]
    conformal table info [TABLE.npz]
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
    b.set_defaults(func=cmd_build)
    i = tsub.add_parser("info", help="print a table's metadata (default: the shipped table)")
    i.add_argument("table", nargs="?", default=None, help="TABLE.npz (default: the table shipped with the package)")
    i.set_defaults(func=cmd_info)


def cmd_build(args) -> int:
    from conformal.tables.build import build_table
    from conformal.tables.spec import load_spec

    spec = load_spec(args.spec)
    rep = build_table(spec, args.out, workers=args.workers, scheduler=args.scheduler,
                      progress=not args.no_progress)
    for label, why in rep.failed:
        print(f"conformal: {label}: failed: {why}", file=sys.stderr)
    print(rep.summary())
    return 1 if rep.failed else 0


def cmd_info(args) -> int:
    from conformal.tables.table import load_table

    print(json.dumps(load_table(args.table).info(), indent=2))
    return 0
