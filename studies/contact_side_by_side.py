"""CONTACT and conformal run side by side on this machine, interleaved, as ratios in one run (issue 23).

The stored CONTACT times of ``studies/performance.py`` were taken once, on another machine of this
kind.  This machine runs in fast and slow phases (the same process takes 0.5 s in one minute and
0.9 s in the next), so a ratio of a time measured now to a stored one is a sample of that spread.
Given a CONTACT executable (built from the open-source code, https://github.com/eve70a/CONTACT),
this study runs each job with CONTACT and with conformal alternately, round after round (the
order swapped every round), and reports the ratio of each round's pair: both sides of a ratio
saw the same phase of the machine.

Jobs (CONTACT's own decks, copied unmodified into tests/reference/):

1. **The Manchester A-2.2 right-wheel deck** (``mbench_a22_right.inp``, 21 lateral shifts, 10 kN,
   steady rolling, planar contact; CONTACT: ``contact 2 mbench_a22_right``, the whole program):
   a. ours, the sequence as a sweep runs it (``studies/performance.py``'s Manchester sequence:
      the first run in a fresh process, exact theory, each case warm-started from the one before;
      the solves timed, not the import or the scene building): the issue's measure;
   b. ours, the whole deck as a process: ``conformal inp mbench_a22_right.inp``.
2. **CONTACT's performance case of the shift** (``tang_problm_1s.inp``, 71 x 81 elements, T = 1):
   CONTACT's whole program against ``studies/performance.py``'s ``perfc_shift`` (influence numbers,
   normal problem and shift in a fresh process; the solves timed).  ``conformal inp`` does not read
   this deck (its undeformed distance IBASE = 2), so there is no whole-process row.

Before timing, CONTACT's answers are checked: every case's FN of the Manchester deck within the
printed digits of its reference output, the shift case's contact and slip element counts equal to
CONTACT's reference counts (3 148 and 1 730); and ours against CONTACT's (FN within 1 %).  A CONTACT
that disagrees stops the study.  Times: wall (perf_counter) and CPU (user + system of the child, from its rusage).

    python studies/contact_side_by_side.py --contact /path/to/contact [--rounds 7] [--quick]

``--contact`` may also come from the environment variable ``CONTACT_EXE``.  How the CONTACT of the
committed run was built (gfortran, MKL from PyPI, the changes gfortran needs) and what its numbers
mean: docs/validation/performance.md, "Side by side with CONTACT built on this machine".  Writes
studies/out/contact_side_by_side/{side_by_side.md, side_by_side.json, run.json}.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import shutil  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import output_dir, write_sidecar  # noqa: E402
from performance import run_timed  # noqa: E402  (one timing of a command for both studies)

DECKS = ROOT / "tests" / "reference" / "contact_decks"
PERFC = ROOT / "tests" / "reference" / "contact_perfc"
#: the jobs: CONTACT's deck, the files it needs beside it, and our in-process job of performance.py
JOBS = {
    "mbench_right": dict(deck=DECKS / "mbench_a22_right.inp",
                         files=(DECKS / "MBench_S1002_v3.prw", DECKS / "MBench_UIC60_v3.prr"),
                         ref=DECKS / "mbench_a22_right.ref_out", inproc={"kind": "mbench", "quick": False},
                         inp=True, counts=None),
    # conformal inp does not read this deck's IBASE = 2; performance.py's perfc_case reads it. CONTACT's
    # contact and slip element counts (perfc_test/get_times.ref_out) check CONTACT's answer
    "perfc_shift": dict(deck=PERFC / "tang_problm_1s.inp", files=(), ref=None, inproc={"kind": "perfc_shift"},
                        inp=False, counts=(3148, 1730)),
}


def contact_run(exe: str, job: dict, scratch: Path) -> dict:
    """CONTACT on the job's deck in a fresh copy of it (``contact 2 <name>``: batch mode, one thread);
    its ``.out`` text is returned with the times."""
    work = Path(tempfile.mkdtemp(prefix="contact_", dir=scratch))
    for f in (job["deck"], *job["files"]):
        shutil.copy(f, work / f.name)
    name = job["deck"].stem
    r = run_timed([exe, "2", name], work, timeout=600, env={"OMP_NUM_THREADS": "1"})
    out = work / f"{name}.out"
    r["out"] = out.read_text(errors="replace") if out.exists() else ""
    shutil.rmtree(work, ignore_errors=True)
    if r["rc"] != 0 or not r["out"]:
        raise SystemExit(f"error: CONTACT failed on {job['deck'].name} (exit {r['rc']}): "
                         f"{(r['stderr'] or r['stdout']).strip().splitlines()[-1:] or 'no output'}")
    return r


def inp_run(job: dict, scratch: Path) -> dict:
    """``conformal inp DECK`` as a process (the installed command's module, this tree's code)."""
    work = Path(tempfile.mkdtemp(prefix="inp_", dir=scratch))
    r = run_timed([sys.executable, "-m", "conformal.cli", "inp", str(job["deck"])], work, timeout=600,
                  env={"PYTHONPATH": str(ROOT)})
    shutil.rmtree(work, ignore_errors=True)
    if r["rc"] != 0:
        raise SystemExit(f"error: conformal inp failed on {job['deck'].name} (exit {r['rc']}): "
                         f"{r['stderr'].strip().splitlines()[-1:]}")
    r["cases"] = [json.loads(ln) for ln in r["stdout"].splitlines() if ln.startswith("{")]
    return r


def inproc_run(job: dict) -> dict:
    """The job in a fresh process of studies/performance.py (its ``--one`` entry): the solves' times."""
    cmd = [sys.executable, str(ROOT / "studies" / "performance.py"), "--one", json.dumps(job["inproc"])]
    r = run_timed(cmd, ROOT, timeout=600)
    lines = [ln for ln in r["stdout"].splitlines() if ln.startswith("{")]
    if r["rc"] != 0 or not lines:
        raise SystemExit(f"error: studies/performance.py --one {job['inproc']['kind']} failed: "
                         f"{r['stderr'].strip().splitlines()[-1:]}")
    res = json.loads(lines[-1])
    res["process_wall_s"], res["process_cpu_s"] = r["wall_s"], r["cpu_s"]
    return res


def check_contact(job: dict, out_text: str, ours_fn: dict[int, float]) -> dict:
    """CONTACT's answers against its reference output (the Manchester deck: every case's FN within
    half a unit of the printed last digit; the shift case: its element counts) and ours against
    CONTACT's (``ours_fn``: {case: FN}; within 1 %)."""
    from conformal.contact_inp.refout import last_digit_unit, read_ref_out

    mine = read_ref_out(out_text)
    if not mine:
        raise SystemExit(f"error: no case totals found in CONTACT's output of {job['deck'].name}")
    worst_ref = 0.0
    if job["ref"] is not None:
        ref = read_ref_out(job["ref"].read_text())
        for k, r in ref.items():
            if k not in mine:
                raise SystemExit(f"error: CONTACT's output of {job['deck'].name} lacks case {k}")
            d = abs(float(mine[k]["FN"]) - float(r["FN"]))
            unit = max(last_digit_unit(mine[k]["FN"]), last_digit_unit(r["FN"]))
            if d > 0.51 * unit:
                raise SystemExit(f"error: CONTACT's FN of case {k} is {mine[k]['FN']}, its reference {r['FN']}")
            worst_ref = max(worst_ref, d / unit)
    if job["counts"] is not None:
        got = (int(mine[1]["NCON"]), int(mine[1]["NSLIP"]))
        if got != job["counts"]:
            raise SystemExit(f"error: CONTACT's contact/slip elements of {job['deck'].name} are {got}, "
                             f"its reference {job['counts']}")
    worst_ours = max(abs(ours_fn[k] / float(mine[k]["FN"]) - 1.0) for k in mine if k in ours_fn)
    if worst_ours > 0.01:
        raise SystemExit(f"error: our FN is {100 * worst_ours:.2f} % from CONTACT's on {job['deck'].name}")
    return dict(cases=len(mine), fn_vs_reference_digits=worst_ref, max_fn_error_ours=worst_ours)


def side_by_side(exe: str, names: list[str], rounds: int) -> dict:
    """``rounds`` rounds of every job: CONTACT, our in-process job and ``conformal inp``, the order
    reversed every other round; per round the ratios ours / CONTACT."""
    res: dict = {}
    with tempfile.TemporaryDirectory(prefix="side_by_side_") as tmp:
        scratch = Path(tmp)
        for name in names:
            job = JOBS[name]
            first_c = contact_run(exe, job, scratch)
            if job["inp"]:
                ours_fn = {k + 1: c["FN"] for k, c in enumerate(inp_run(job, scratch)["cases"])}
            else:
                ours_fn = {1: inproc_run(job)["FN"]}
            check = check_contact(job, first_c["out"], ours_fn)
            print(f"[{name}] CONTACT's answers checked: {check}", flush=True)
            rows = []
            for k in range(rounds):
                order = ("contact", "inproc", "inp")[:3 if job["inp"] else 2]
                order = order if k % 2 == 0 else order[::-1]
                got = {}
                for who in order:
                    got[who] = (contact_run(exe, job, scratch) if who == "contact" else
                                inproc_run(job) if who == "inproc" else inp_run(job, scratch))
                row = dict(round=k + 1, load=float(os.getloadavg()[0]))
                for who, r in got.items():
                    row[f"{who}_wall_s"], row[f"{who}_cpu_s"] = r["wall_s"], r["cpu_s"]
                    if who != "contact":
                        row[f"ratio_{who}"] = r["wall_s"] / got["contact"]["wall_s"]
                rows.append(row)
                print(f"[{name}] round {k + 1}: " + ", ".join(f"{who} {row[f'{who}_wall_s']:.3f} s" for who in got)
                      + "; ratios " + ", ".join(f"{who} {row[f'ratio_{who}']:.2f}" for who in got if who != "contact"),
                      flush=True)
            med = {key: float(np.median([r[key] for r in rows])) for key in rows[0] if key != "round"}
            res[name] = dict(check=check, rounds=rows, median=med,
                             ranges={key: [min(r[key] for r in rows), max(r[key] for r in rows)]
                                     for key in rows[0] if key.startswith("ratio_")})
    return res


def _f(v, fmt=".2f") -> str:
    return "-" if v is None else format(v, fmt)


def report(res: dict, exe: str) -> str:
    lines = ["# CONTACT and conformal side by side (studies/contact_side_by_side.py)", "",
             f"CONTACT: `{exe}` (one thread). Each round runs CONTACT, our job in a fresh process and "
             "`conformal inp` on the same deck, one after the other (the order reversed every other "
             "round); a ratio divides the two wall times of one round. Medians over the rounds. CPU: user + "
             "system seconds of the process (in process: of the timed solves).", ""]
    titles = {"mbench_right": "Manchester A-2.2 right wheel, 21 shifts (`mbench_a22_right.inp`)",
              "perfc_shift": "CONTACT's shift performance case, 71 x 81 (`tang_problm_1s.inp`)"}
    for name, r in res.items():
        m, ck = r["median"], r["check"]
        lines += [f"## {titles[name]}", "",
                  f"CONTACT's {ck['cases']} case(s) checked: FN within {ck['fn_vs_reference_digits']:.2f} of the last "
                  f"printed digit of its reference output; ours within "
                  f"{100 * ck['max_fn_error_ours']:.2f} % of CONTACT's FN.", "",
                  "| round | load | CONTACT wall s (CPU) | ours in process wall s (CPU) | ratio | `conformal inp` wall s (CPU) | ratio |",
                  "|---:|---:|---:|---:|---:|---:|---:|"]
        for row in [*r["rounds"], dict(m, round="median")]:
            lines.append(f"| {row['round']} | {row['load']:.1f} | {row['contact_wall_s']:.3f} ({row['contact_cpu_s']:.3f}) "
                         f"| {row['inproc_wall_s']:.3f} ({row['inproc_cpu_s']:.3f}) | {row['ratio_inproc']:.2f} | "
                         f"{_f(row.get('inp_wall_s'), '.3f')} ({_f(row.get('inp_cpu_s'), '.3f')}) "
                         f"| {_f(row.get('ratio_inp'))} |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--contact", default=os.environ.get("CONTACT_EXE"),
                    help="CONTACT's executable (default: $CONTACT_EXE)")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--jobs", default="mbench_right,perfc_shift", help=f"comma separated, of {', '.join(JOBS)}")
    ap.add_argument("--quick", action="store_true", help="one round of the shift case only")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    if not args.contact:
        print("error: give CONTACT's executable: --contact PATH or CONTACT_EXE=PATH", file=sys.stderr)
        return 2
    exe = shutil.which(args.contact) or args.contact
    if not (Path(exe).is_file() and os.access(exe, os.X_OK)):
        print(f"error: --contact {args.contact}: not an executable file", file=sys.stderr)
        return 2
    names = [n.strip() for n in args.jobs.split(",") if n.strip()]
    bad = [n for n in names if n not in JOBS]
    if bad or not names or args.rounds < 1:
        print(f"error: --jobs: choose from {', '.join(JOBS)}; --rounds >= 1 (got {args.jobs!r}, {args.rounds})",
              file=sys.stderr)
        return 2
    if args.quick:
        names, args.rounds = ["perfc_shift"], 1
    res = side_by_side(str(Path(exe).resolve()), names, args.rounds)
    out = output_dir("contact_side_by_side", args)
    out.mkdir(parents=True, exist_ok=True)
    text = report(res, args.contact)
    (out / "side_by_side.md").write_text(text + "\n", encoding="utf-8")
    (out / "side_by_side.json").write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")
    write_sidecar(out, __file__, args)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
