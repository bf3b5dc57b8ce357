"""The ``conformal`` command.

    conformal solve SCENE.toml [--json OUT.json] [--plot OUT.png] [--theory NAME] [--vtu OUT.vtu]
    conformal demo [--out DIR]
    conformal precompute SCENE.toml --sweep shift=0:10:0.5 [--workers N] [--scheduler ADDRESS|local]
    conformal cache list|clear [--cache DIR]
    conformal sweep SCENE.toml [--shift START:STOP:STEP] [--out DIR] [--solve [--workers N]]
    conformal --version
    conformal inp DECK.inp [--out DIR]
    conformal stresses SCENE.toml [--depth D] [--k K] [--vtu OUT.vtu] [--plot OUT.png] [--json OUT.json]

Bad input ends with exit code 2 and one line on stderr naming the key and the problem; a solve that
did not converge writes its JSON with "converged": false and ends with exit code 3 (unless
--allow-unconverged), in every command that solves (solve, sweep --solve, inp, stresses, table build
and refine); an iteration that gives no result at all (ConvergenceError: the vertical balance, the
wheelset's integrator, the FE contact's active set) ends with one line and exit code 3.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from importlib import resources
from pathlib import Path

from conformal.errors import EXIT_UNCONVERGED, ConformalError, ConvergenceError, InputError, unconverged_exit
from conformal.files import check_output_path, write_text
from conformal.registry import CURVED_STRIP, FE_BODIES, MODELS, VTU

#: file types ``--plot`` can write (matplotlib's raster and vector formats)
PLOT_SUFFIXES = (".png", ".jpg", ".jpeg", ".pdf", ".svg", ".eps", ".ps", ".tif", ".tiff", ".webp")


def _write_json(summary: dict, path: str | None) -> None:
    text = json.dumps(summary, indent=2)
    print(text)
    if path:   # atomic: a failed write (full disk) leaves no empty or cut file and exits 2
        write_text(path, text + "\n")


# a solve that did not converge writes its outputs and exits with conformal.errors.EXIT_UNCONVERGED
# (--allow-unconverged: 0), the same for every command that solves


def _solve_and_report(scene, json_path: str | None, plot_path: str | None, vtu_path: str | None = None,
                      render=None, allow_unconverged: bool = False) -> int:
    """Solve, write the JSON (always, once the solve succeeded), then the optional VTU and plot:
    a failing plot is reported (exit 1) but does not lose the JSON.  ``render``: a
    conformal.plots.Render3D started before the solve (the demo) for the plot's 3-D view.  A
    result that did not converge is reported on stderr and ends with EXIT_UNCONVERGED unless
    ``allow_unconverged``."""
    from conformal.dispatch import solve_scene

    check_output_path(json_path, "--json")
    check_output_path(plot_path, "--plot", PLOT_SUFFIXES)
    check_output_path(vtu_path, "--vtu", (".vtu",))
    if vtu_path and not MODELS.accepts(scene.model.theory, VTU):
        raise InputError(f"--vtu: needs [model] theory = \"conformal\" (tractions on the curved surfaces) or "
                         f"\"fe_contact\" (contact pressure on the meshed bodies); this scene's theory is "
                         f"{scene.model.theory!r}")
    fe_run = None
    if vtu_path and MODELS.accepts(scene.model.theory, FE_BODIES):   # the VTU needs the meshed bodies
        from conformal.cases.fe_contact import solve_scene_with_run

        result, fe_run = solve_scene_with_run(scene)
    else:
        result = solve_scene(scene)
    for w in result.warnings:
        print(f"conformal: warning: {w}", file=sys.stderr)
    _write_json(result.summary(), json_path)
    code = 0
    if vtu_path:
        from conformal.fe_contact.problems import write_vtu
        from conformal.plots import export_result_vtu

        try:
            if fe_run is not None:   # OUT.vtu: body 1 with the pressure; OUT_body2.vtu: body 2
                write_vtu(fe_run, vtu_path)
            else:
                export_result_vtu(result, vtu_path)
        except (OSError, ValueError, RuntimeError) as exc:
            print(f"conformal: error: --vtu: {exc} (the JSON summary was written)", file=sys.stderr)
            code = 1
    if plot_path:
        from conformal.plots import plot_result

        try:
            plot_result(result, plot_path, title=f"{scene.name}: {result.theory}", render=render)
        except Exception as exc:  # noqa: BLE001 - any plotting failure: the JSON is already out
            print(f"conformal: error: --plot: {type(exc).__name__}: {exc} (the JSON summary was written)",
                  file=sys.stderr)
            code = 1
    if not result.converged and code == 0:
        how = "accepted (--allow-unconverged)" if allow_unconverged else "exit status 3; --allow-unconverged accepts it"
        print(f"conformal: {'warning' if allow_unconverged else 'error'}: the solve did not converge ([model] maxit = "
              f"{scene.model.maxit}, tol = {scene.model.tol:g}; \"converged\": false in the JSON): {how}",
              file=sys.stderr)
        code = 0 if allow_unconverged else EXIT_UNCONVERGED
    return code


def cmd_solve(args) -> int:
    from conformal.scene import load_scene

    scene = load_scene(args.scene)
    if args.theory:
        if args.theory not in MODELS:
            raise InputError(f"--theory: must be one of {', '.join(MODELS.names)}, got {args.theory!r}")
        scene = scene.with_model(theory=args.theory)
    return _solve_and_report(scene, args.json, args.plot, args.vtu, allow_unconverged=args.allow_unconverged)


def demo_scene_path() -> Path:
    return Path(str(resources.files("conformal") / "data" / "scenes" / "demo.toml"))


def cmd_demo(args) -> int:
    from conformal.scene import load_scene

    out = Path(args.out)
    check_output_path(str(out / "demo.json"), "--out")
    out.mkdir(parents=True, exist_ok=True)
    scene = load_scene(demo_scene_path())
    # the 3-D view's helper process (pyvista import, off-screen window) starts now and works
    # while the solve runs: the demo's wall time on two cores drops by about a second
    from conformal.plots import WINDOW_3D, Render3D

    render = Render3D(WINDOW_3D) if MODELS.accepts(scene.model.theory, CURVED_STRIP) else None
    try:
        code = _solve_and_report(scene, str(out / "demo.json"), str(out / "demo.png"), render=render)
    finally:
        if render is not None:
            render.close()
    print(f"wrote {out / 'demo.json'} and {out / 'demo.png'}", file=sys.stderr)
    return code


def cmd_sweep(args) -> int:
    from conformal.geometry.sweep import jump_warnings, parse_range, plot, sweep, write_csv
    from conformal.scene import load_scene

    scene = load_scene(args.scene)
    if scene.geometry.kind != "wheel_rail":
        raise InputError(f"[geometry] kind: a sweep needs a wheel_rail scene, got {scene.geometry.kind!r}")
    if args.solve:
        return _sweep_solve(scene, args)
    if args.workers is not None:
        raise InputError("--workers: only with --solve (the geometry sweep runs in one process)")
    check_output_path(str(Path(args.out) / "sweep.csv"), "--out")
    rows = sweep(scene.geometry, parse_range(args.shift), scene.base_dir)
    out = Path(args.out)
    write_csv(rows, out / "sweep.csv")
    plot(rows, out / "sweep.png", title=f"{scene.name}: lateral shift sweep")
    for r in rows:
        print("  ".join(f"{k}={v:.5g}" if isinstance(v, float) else f"{k}={v}" for k, v in r.items()))
    for w in jump_warnings(rows):
        print(f"conformal: warning: {w}", file=sys.stderr)
    print(f"wrote {out / 'sweep.csv'} and {out / 'sweep.png'}", file=sys.stderr)
    return 0


def _sweep_solve(scene, args) -> int:
    """``conformal sweep --solve``: the scene solved at every shift (conformal.cases.sweep): the
    table as sweep_solved.csv (units in the header) and .json, the plot sweep_solved.png."""
    from conformal.cases.sweep import parse_shifts, solve_sweep

    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers: must be >= 1, got {args.workers}")
    out = Path(args.out)
    check_output_path(str(out / "sweep_solved.csv"), "--out")
    table = solve_sweep(scene, parse_shifts(args.shift), workers=args.workers, progress=True)
    write_text(out / "sweep_solved.csv", table.to_csv())
    table.to_json(out / "sweep_solved.json")
    for r in table.rows():
        vals = "  ".join(f"{k}={r[k]:.5g}" if isinstance(r[k], float) else f"{k}={r[k]}"
                         for k in ("shift", "FN", "FY_track", "FZ_track", "contact_angle", "y_rail", "n_patches"))
        print(vals + (f"  error: {r['error']}" if r["error"] else ""))
        for w in r["warnings"]:
            print(f"conformal: warning: shift {r['shift']:g} mm: {w}", file=sys.stderr)
    code = 0
    try:
        table.plot(out / "sweep_solved.png")
    except Exception as exc:  # noqa: BLE001 - any plotting failure: the table is already out
        print(f"conformal: error: plot: {type(exc).__name__}: {exc} (the table was written)", file=sys.stderr)
        code = 1
    print(f"wrote {out / 'sweep_solved.csv'}, {out / 'sweep_solved.json'} and {out / 'sweep_solved.png'}",
          file=sys.stderr)
    if all(e is not None for e in table.errors):
        print(f"conformal: error: no shift could be solved ({table.errors[0]})", file=sys.stderr)
        return 2
    bad = [r["shift"] for r in table.rows() if r["error"] is None and r["converged"] == 0]
    if bad and code == 0:       # "converged" 0 in the CSV and JSON: the same rule as solve
        code = unconverged_exit(f"the solve at shift {', '.join(f'{v:g}' for v in bad)} mm", args.allow_unconverged)
    return code


class _Parser(argparse.ArgumentParser):
    """argparse with one line on stderr for a bad command line (exit 2), as for every other bad
    input: the usage text is what ``conformal COMMAND --help`` prints."""

    def error(self, message: str):
        where = self.prog.partition(" ")[2]         # the sub-command ("" for the top level)
        self.exit(2, f"conformal: error: {where + ': ' if where else ''}{message} (see {self.prog} --help)\n")


#: the commands defined in this module: a process running one of them builds only their parsers
#: (the other modules' commands import numpy, scipy and more just to declare their options)
CORE_COMMANDS = ("solve", "demo", "sweep", "precompute", "cache")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``conformal`` argument parser; ``command`` in CORE_COMMANDS leaves out the commands of
    the other modules (table, simulate, stability, inp, stresses)."""
    from conformal import __version__

    p = _Parser(prog="conformal", description="Conformal wheel-rail rolling contact workbench")
    p.add_argument("--version", action="version", version=f"conformal {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("solve", help="solve a scene file and print a JSON summary")
    s.add_argument("scene", help="scene file (TOML)")
    s.add_argument("--json", metavar="OUT.json", help="also write the JSON summary to this file")
    s.add_argument("--plot", metavar="OUT.png", help="write a PNG of the tractions")
    s.add_argument("--theory", help=MODELS.theory_help())
    s.add_argument("--vtu", metavar="OUT.vtu", help="write the tractions on the curved surfaces for ParaView "
                   "(theory \"conformal\"; also OUT_rail.vtu, OUT_wheel.vtu) or the contact pressure on "
                   "the meshed rail (theory \"fe_contact\"; also OUT_body2.vtu)")
    s.add_argument("--allow-unconverged", action="store_true",
                   help="exit 0 also when the solver did not converge (default: exit status 3)")
    s.set_defaults(func=cmd_solve)

    w = sub.add_parser("sweep", help="wheel-rail geometry versus lateral shift: CSV and PNG")
    w.add_argument("scene", help="wheel_rail scene file (TOML)")
    w.add_argument("--shift", default="0:10:0.5", help="lateral shifts start:stop:step in mm (default 0:10:0.5)")
    w.add_argument("--out", default="out", help="output folder (default: out)")
    w.add_argument("--solve", action="store_true", help="solve every shift with the scene's theory and influence "
                   "numbers: forces, creepages, patches (sweep_solved.csv / .json / .png)")
    w.add_argument("--workers", type=int, default=None, help="with --solve: processes for missing FE influence "
                   "numbers (default: cores/2)")
    w.add_argument("--allow-unconverged", action="store_true",
                   help="with --solve: exit 0 also when a shift did not converge (default: exit status 3)")
    w.set_defaults(func=cmd_sweep)

    d = sub.add_parser("demo", help="solve the built-in demo scene, write JSON and PNG")
    d.add_argument("--out", default="out", help="output folder (default: out)")
    d.set_defaults(func=cmd_demo)

    pc = sub.add_parser("precompute", help="compute and cache FE influence numbers for a sweep of positions")
    pc.add_argument("scene", help="wheel-rail scene file (TOML); [model] fe_* keys set the FE model")
    pc.add_argument("--sweep", required=True, metavar="KEY=START:STOP:STEP",
                    help="positions, e.g. shift=0:10:0.5 (keys: shift, yaw, roll)")
    pc.add_argument("--workers", type=int, default=None, help="parallel local processes (default: cores/2)")
    pc.add_argument("--scheduler", metavar="ADDRESS",
                    help="Dask scheduler address, or 'local' for a local Dask cluster (needs dask)")
    pc.add_argument("--cache", metavar="DIR", help="cache folder (default: $CONFORMAL_CACHE or the user cache)")
    pc.add_argument("--dry-run", action="store_true", help="only list what would be computed")
    pc.add_argument("--no-progress", action="store_true", help="no progress bar")
    pc.set_defaults(func=cmd_precompute)

    ca = sub.add_parser("cache", help="list or clear the cache of FE influence numbers")
    ca.add_argument("action", choices=("list", "clear"))
    ca.add_argument("--cache", metavar="DIR", help="cache folder (default: $CONFORMAL_CACHE or the user cache)")
    ca.set_defaults(func=cmd_cache)

    if command in CORE_COMMANDS:
        return p
    from conformal.tables.cli import add_parsers as add_table_parsers  # conformal table build|info
    add_table_parsers(sub)

    from conformal.dynamics.cli import add_parsers as add_dynamics_parsers  # conformal simulate|stability
    add_dynamics_parsers(sub)

    from conformal.contact_inp.cli import add_parsers as add_inp_parsers  # conformal inp FILE.inp
    add_inp_parsers(sub)

    from conformal.stresses.run import add_parsers as add_stresses_parsers  # conformal stresses
    add_stresses_parsers(sub, check_output_path, PLOT_SUFFIXES)
    return p


def cmd_precompute(args) -> int:
    from conformal.influence.cache import Cache
    from conformal.cases.precompute import precompute
    from conformal.jobs import parse_sweep
    from conformal.scene import load_scene

    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers: must be >= 1, got {args.workers}")
    sweep = parse_sweep(args.sweep)
    scene = load_scene(args.scene)
    cache = Cache(args.cache)
    if cache.folder.exists() and not cache.folder.is_dir():
        raise InputError(f"--cache: {cache.folder} is a file, not a cache folder")
    if not args.dry_run:
        check_output_path(str(cache.folder / "entry.npz"), "--cache")
    rep = precompute(scene, sweep, cache=cache, workers=args.workers, scheduler=args.scheduler,
                     progress=not args.no_progress, dry_run=args.dry_run)
    for v, why in rep.positions_failed:
        print(f"conformal: {sweep.key} = {v:g}: no contact grid ({why})", file=sys.stderr)
    for label, why in rep.failed:
        print(f"conformal: {label}: failed: {why}", file=sys.stderr)
    print(("dry run: " if args.dry_run else "") + rep.summary() + f"; cache: {cache.folder}")
    return 1 if rep.failed else 0


def cmd_cache(args) -> int:
    from conformal.influence.cache import Cache

    cache = Cache(args.cache)
    if cache.folder.exists() and not cache.folder.is_dir():
        raise InputError(f"--cache: {cache.folder} is a file, not a cache folder")
    if args.action == "clear":
        n, left = cache.clear()
        print(f"removed {n} files from {cache.folder}")
        if left:   # only files it can identify as its own entries are removed
            print(f"conformal: left {len(left)} .npz files that are not readable entries of this cache "
                  f"(e.g. {left[0].name})", file=sys.stderr)
        return 0
    entries = cache.entries()
    total = sum(e.size for e in entries)
    for e in entries:
        when = time.strftime("%Y-%m-%d %H:%M", time.localtime(e.created))
        print(f"{e.key[:16]}  {e.size / 2**20:8.1f} MiB  {when}  {e.summary if e.ok else 'UNREADABLE'}")
    print(f"{len(entries)} entries, {total / 2**20:.1f} MiB in {cache.folder}")
    return 0


def _join_negative_ranges(argv: list[str]) -> list[str]:
    """``--q -0.5:-0.1`` as ``--q=-0.5:-0.1``: argparse takes a value that starts with '-' and is
    not a plain number for an option.

    >>> _join_negative_ranges(["table", "refine", "t.npz", "--q", "-0.5:-0.1"])[-1]
    '--q=-0.5:-0.1'
    """
    out: list[str] = []
    for arg in argv:
        if out and out[-1] == "--q" and arg.startswith("-") and ":" in arg:
            out[-1] = f"--q={arg}"
        else:
            out.append(arg)
    return out


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A Python warning as one line, like the program's own: ``conformal: warning: TEXT`` (the
    package's warnings, e.g. CacheWarning) or ``conformal: warning: RuntimeWarning: TEXT`` (numpy's);
    Python's default format adds the source file and line, two lines that look like a traceback."""
    own = getattr(category, "__module__", "").startswith("conformal")
    text = " ".join(str(message).split())
    print(f"conformal: warning: {'' if own else category.__name__ + ': '}{text}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    import warnings

    argv = _join_negative_ranges(list(sys.argv[1:] if argv is None else argv))
    parser = build_parser(argv[0] if argv and argv[0] in CORE_COMMANDS else None)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:       # --help, --version, or a bad command line (one line, _Parser.error)
        return int(exc.code or 0)
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        return _run(args)


def _run(args) -> int:
    """``args.func(args)`` with the exit status of its outcome (see the module docstring)."""
    try:
        return int(args.func(args) or 0)
    except ConvergenceError as exc:   # an iteration that gave no result at all: the same status as "converged": false
        print(f"conformal: error: {exc} (did not converge; nothing written): exit status {EXIT_UNCONVERGED}",
              file=sys.stderr)
        return EXIT_UNCONVERGED
    except ConformalError as exc:
        print(f"conformal: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"conformal: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("conformal: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
