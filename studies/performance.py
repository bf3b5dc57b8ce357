"""Speed of the whole pipeline in one table (issue 13): steady rolling, the normal problem, FE
influence numbers, the example FE scenes, ``conformal demo`` and (optionally) the test command.

What is measured (every wall time next to the machine's load average when it was taken, because
on a shared 2-core machine other jobs inflate wall times by up to 3x; CPU times are less
sensitive):

1. **Steady rolling** (case "circ" of studies/steady_rolling_speed.py: quasi-identical steel,
   A = B = 0.001 1/mm, FN = 100 kN, 1.1 x the Hertz circle in n x n elements, mu 0.3, xi 0.001,
   tol 1e-6), n = 50 .. 400: influence products spent on the n x n grid
   (``TangentialSolution.products``) plus those of the nested start (``coarse_products``, in
   units of the n x n grid), the wall time, and the wall time in units of one FFT pair of the
   padded grid; the growth exponents q of cost ~ N^q (N = n^2, np.polyfit of the logs).
2. **Normal problem** on the same grids: projected-CG iterations and wall time (FFT pairs).
3. **FE influence numbers, 51 x 39**: the wheel (S1002 tread) and rail (UIC 60 crown) bodies of
   studies/fe_influence_speed_error.py (0.4 mm elements, default settings), first time (no
   cache), as :func:`conformal.influence.fe.body_influences` computes them: two processes by
   default, one after the other with ``--sequential``; wall, CPU of both processes, peak memory
   of each process, and the stages of each body (meshing, assembly, right-hand sides,
   factorisation, solve, observation).
4. **Example FE scenes** (every scene of meshes/scenes with theory "conformal" and
   influence "fe"; ``--worn`` adds flange_worn_three_patches.toml with influence "fe"): the first
   solve with an empty cache, each in its own process: wall time, peak memory of the process and
   of its child (the second body), FN.
5. **conformal demo**: wall time of the installed command (best of ``--repeats``).
6. ``--tests``: wall time of the README's test command ``python -m pytest``.
7. **Against CONTACT** (issue 23; CONTACT's times for the same jobs are stored in ``CONTACT`` below
   with their source): the Manchester A-2.2 right-wheel sequence (21 shifts, CONTACT's roll and
   pitch velocity per case, 0.2 mm elements, exact theory) solved in one process (its own
   process: the solves timed, import and scene building not; three fresh processes, the row is
   the one with the median first run, each also timing a second run with its caches warm), with
   the largest FN error against CONTACT; the start-up (``python -X importtime -c "import conformal"``
   and the wall time of a process that only imports the package, less that of an empty
   process); one small solve as a process (``conformal solve`` of case circ, n = 50, steady
   rolling, exact theory); CONTACT's own performance case of the shift (T = 1, the Manchester right
   wheel at 6.2 mm, 71 x 81 elements: tests/reference/contact_perfc/tang_problm_1s.inp) solved as
   CONTACT runs it, the whole job and its shift against CONTACT's stored times, with the contact and
   slip element counts against CONTACT's; and every half-space row as a ratio to CONTACT's time for it.

``--quick``: n = 25, 50, 100, a 21 x 15 FE patch instead of 51 x 39, the smallest FE scene only,
the Manchester sequence at 0, 5 and 7 mm only (0.4 mm elements), one demo run (used by tests/studies/test_performance_study.py).  Writes
studies/out/performance/{performance.md, performance.json, run.json}.

    python studies/performance.py [--quick] [--sizes 50 100 200 300 400] [--worn] [--tests]
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _provenance import write_sidecar  # noqa: E402
from steady_rolling_speed import fft_pair_time  # noqa: E402  (one definition of the unit)

OUT = ROOT / "studies" / "out" / "performance"
SCENES = ROOT / "meshes" / "scenes"
WORN = "flange_worn_three_patches.toml"
# targets of issue 13 (2-core machine)
TARGETS = {"fft_pairs_200": 150, "growth": 1.1, "fe_51x39_s": 8.0, "fe_scene_s": 30.0, "fe_scene_gib": 2.0,
           "demo_s": 2.5, "tests_s": 120.0}


def load() -> float:
    return float(os.getloadavg()[0]) if hasattr(os, "getloadavg") else float("nan")


def _peak_gib(who=resource.RUSAGE_SELF) -> float:
    return resource.getrusage(who).ru_maxrss / 2**20


# ----------------------------------------------------------------------------- 1, 2: half-space
def circ_problem(n: int):
    from conformal.grid import PlanarGrid
    from conformal.influence.halfspace import HalfSpaceInfluence
    from conformal.materials import Material
    from conformal.theories.hertz import hertz_from_curvatures

    mat = Material.steel()
    hz = hertz_from_curvatures(1e-3, 1e-3, mat, normal_force=1e5)
    grid = PlanarGrid.around_ellipse(hz.a, hz.b, n=n, scale=1.1)
    X, Y = grid.mesh()
    op = HalfSpaceInfluence.for_grid(n, n, grid.dx, grid.dy, mat)
    return grid, op, 1e-3 * (X**2 + Y**2)


def halfspace_rows(sizes, repeats: int) -> list[dict]:
    from conformal.solvers import tangential as tang
    from conformal.solvers.normal import solve_normal

    rows = []
    for n in sizes:
        grid, op, h = circ_problem(n)
        unit = fft_pair_time(op)
        la = load()
        wn, nsol = np.inf, None
        for _ in range(repeats):
            t0 = time.perf_counter()
            nsol = solve_normal(op, grid, h, normal_force=1e5, tol=1e-6)
            wn = min(wn, time.perf_counter() - t0)
        wt, ct, sol = np.inf, np.inf, None
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            sol = tang.solve_tangential(op, grid, nsol.pn, xi=1e-3, eta=0.0, phi=0.0, mu_static=0.3,
                                        mu_kinetic=0.3, tol=1e-6)
            wt, ct = min(wt, time.perf_counter() - t0), min(ct, time.process_time() - c0)
        FX = float(sol.px.sum() * grid.area)
        rows.append(dict(n=n, fft_pair_s=unit, load=la,
                         normal_iterations=int(nsol.iterations), normal_wall_s=wn, normal_fft_pairs=wn / unit,
                         products=int(sol.products), coarse_products=float(sol.coarse_products),
                         cost_products=float(sol.products + sol.coarse_products),
                         newton_iterations=int(sol.iterations), converged=bool(sol.converged),
                         steady_wall_s=wt, steady_cpu_s=ct, steady_fft_pairs=wt / unit, FX=FX))
        print(f"[steady] n {n}: products {sol.products} + {sol.coarse_products:.1f}, {wt:.3f} s = "
              f"{wt / unit:.0f} FFT pairs; normal {nsol.iterations} its {wn:.3f} s (load {la:.1f})", flush=True)
    return rows


def growth(sizes, values) -> float | None:
    """Exponent q of value ~ N^q, N = n^2 (np.polyfit of the logs)."""
    if len(sizes) < 2:
        return None
    return float(np.polyfit(np.log(np.asarray(sizes, float) ** 2), np.log(np.asarray(values, float)), 1)[0])


# ----------------------------------------------------------------------------- 3: FE 51 x 39
def fe_pair(mx: int, ms: int, workers: int) -> dict:
    """Wheel + rail of studies/fe_influence_speed_error.py, first time (no cache), in this process
    (and a forked child for the second body when workers = 2)."""
    from fe_influence_speed_error import D, NU, G, body_and_patch

    from conformal.influence.fe import FESettings, body_influences

    jobs = [(*body_and_patch(kind, mx, ms, D), G, NU, FESettings()) for kind in ("rail", "wheel")]
    la = load()
    t0, c0 = time.perf_counter(), time.process_time()
    kr, kw = body_influences(jobs, cache=False, workers=workers)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    stages = ("mesh_s", "assemble_s", "rhs_s", "factor_s", "solve_s", "observe_s", "total_s", "dofs", "peak_rss_gib")
    return dict(mx=mx, ms=ms, workers=workers, wall_s=wall, cpu_s=cpu + ch.ru_utime + ch.ru_stime, load=la,
                peak_gib=max(_peak_gib(), ch.ru_maxrss / 2**20),
                rail={k: kr.stats.get(k) for k in stages}, wheel={k: kw.stats.get(k) for k in stages})


# ----------------------------------------------------------------------------- 4: FE scenes
def fe_scene(path: str, influence_fe: bool) -> dict:
    """First solve of a scene with an empty cache (CONFORMAL_CACHE is set by the caller)."""
    import conformal

    scene = conformal.load_scene(path)
    if influence_fe:
        scene = scene.with_("model.influence", "fe")
    la = load()
    t0, c0 = time.perf_counter(), time.process_time()
    r = conformal.solve(scene)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    bodies = {}

    def find(d):
        if isinstance(d, dict):
            for k, v in d.items():
                if k in ("rail", "wheel") and isinstance(v, dict) and "total_s" in v:
                    bodies.setdefault(k, []).append({kk: v.get(kk) for kk in ("total_s", "dofs", "mesh_s",
                                                                               "factor_s", "solve_s", "peak_rss_gib")})
                else:
                    find(v)
        elif isinstance(d, list):
            for v in d:
                find(v)

    find(r.extra)
    return dict(scene=Path(path).name, influence_fe_override=influence_fe, wall_s=wall,
                cpu_s=cpu + ch.ru_utime + ch.ru_stime, load=la, peak_gib_self=_peak_gib(),
                peak_gib_child=ch.ru_maxrss / 2**20, FN=float(r.FN), fe_bodies=bodies)


def fe_scenes(quick: bool, worn: bool) -> list[str]:
    import tomllib

    out = []
    for p in sorted(SCENES.glob("*.toml")):
        m = tomllib.loads(p.read_text()).get("model", {})
        if m.get("theory") == "conformal" and m.get("influence") == "fe":
            out.append(str(p))
    if quick:    # the smallest: the crowned wheel on the flat rail
        out = [p for p in out if Path(p).name == "hertz_crowned_wheel.toml"][:1]
    return out + ([str(SCENES / WORN)] if worn and not quick else [])


def spawn(what: dict, timeout: float, env: dict | None = None) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--one", json.dumps(what)]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=ROOT,
                           env={**os.environ, **(env or {})})
    except subprocess.TimeoutExpired:
        return dict(what, error=f"timeout after {timeout:.0f} s")
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        tail = (p.stderr.strip().splitlines() or ["failed"])[-1]
        return dict(what, error=f"exit {p.returncode}: {tail}")
    return json.loads(lines[-1])


# ----------------------------------------------------------------------------- 5, 6: commands
def run_timed(cmd: list[str], cwd: Path, timeout: float, env: dict | None = None) -> dict:
    """One run of ``cmd``: wall seconds, CPU seconds of the command and its helper processes (user +
    system, from the rusage of the children waited for), exit status, stdout and stderr."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout,
                       env=None if env is None else {**os.environ, **env})
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
    return dict(wall_s=wall, cpu_s=cpu, rc=p.returncode, stdout=p.stdout, stderr=p.stderr)


def timed_command(cmd: list[str], repeats: int, cwd: Path, timeout: float) -> dict:
    """Best wall time of ``repeats`` runs (:func:`run_timed`), with the CPU time of that run."""
    walls, cpus, loads, rc = [], [], [], 0
    for _ in range(repeats):
        la = load()
        r = run_timed(cmd, cwd, timeout)
        walls.append(r["wall_s"])
        cpus.append(r["cpu_s"])
        loads.append(la)
        rc = rc or r["rc"]
    k = int(np.argmin(walls))
    return dict(command=" ".join(cmd), wall_s=walls[k], walls=walls, cpu_s=cpus[k], cpus=cpus, load=loads[k], rc=rc)


def demo_command() -> list[str]:
    exe = Path(sys.executable).with_name("conformal")
    return [str(exe), "demo"] if exe.exists() else [sys.executable, "-m", "conformal.cli", "demo"]


# ----------------------------------------------------------------------------- 7: against CONTACT
#: CONTACT's wall times for the jobs measured here, with their source (CONTACT rev. 2707 built from
#: source on a machine of this kind, one thread)
CONTACT = {
    "mbench_right_s": 1.37,
    "mbench_source": "issue 23: the whole deck examples/mbench_a22_right (21 cases, 65 ms CPU per case), "
                     "answers checked equal before timing",
    "normal_s": {50: 0.012, 100: 0.046, 150: 0.071, 200: 0.14},
    "gdsteady_s": {50: 0.29, 100: 1.17, 150: 2.87, 200: 6.80},
    "steadygs_s": {25: 0.025, 50: 0.40, 100: 6.8, 150: 44.0, 200: 211.0},
    "circ_source": "tests/reference/contact_performance.md, case circ (whole program run)",
    "gdsteady_growth_200_400": 1.53,
    "growth_source": "issue 23 (GDsteady, N^q from 200^2 to 400^2)",
    # CONTACT's own performance case of the shift (T = 1): the Manchester right wheel at y = 6.2 mm,
    # 71 x 81 elements of 0.1 mm, the deck perfc_test/tang_problm_1s.inp (tests/reference/contact_perfc);
    # whole program (normal + shift), and its normal problem alone (norm_problm_1p, the same grid);
    # no CONTACT time is stored for the shift of case circ, so this is the shift's anchor
    "perfc_shift_s": 0.13,
    "perfc_normal_s": 0.046,
    "perfc_source": "tests/reference/contact_performance.md (CONTACT's performance cases, shift TangCG 71 x 81)",
    # CONTACT's contact and slip element counts of that case (perfc_test/get_times.ref_out: ncon of
    # norm_problm_1p, nslp of tang_problm_1s)
    "perfc_ncon": 3148,
    "perfc_nslip": 1730,
}
PERFC_SHIFT = ROOT / "tests" / "reference" / "contact_perfc" / "tang_problm_1s.inp"
IMPORT_TARGET_S = 0.15
MBENCH_REF = ROOT / "tests" / "reference" / "contact_cases.json"


#: fresh processes of the Manchester sequence in a full run of the study
MBENCH_PROCESSES = 3


def mbench_sequence(quick: bool) -> dict:
    """The Manchester A-2.2 right-wheel sequence in this process (studies/manchester_a22.py's
    scenes: CONTACT's yaw, roll and pitch velocity per case), as a sweep would run it (each case
    warm-started from the one before)."""
    from manchester_a22 import scene_for

    import conformal.cases.wheelrail as wr

    cases = json.loads(MBENCH_REF.read_text())["cases"]["mbench_a22"]["right"]
    if quick:
        cases = [c for c in cases if c["inputs"]["Y_WS_mm"] in (0.0, 5.0, 7.0)]
    scenes = [scene_for("right", c, 0.4 if quick else 0.2) for c in cases]
    la = load()
    warm, errs, counts = None, [], {"searches": 0, "normal_solves": 0, "tangential_solves": 0}
    t0, c0 = time.perf_counter(), time.process_time()
    for sc, c in zip(scenes, cases):
        r = wr.solve_wheel_rail(sc, warm=warm)
        warm = wr.WarmStart.from_result(r, warm)
        main = max(r.patches, key=lambda p: p.FN)
        errs.append(abs(main.FN / c["outputs"]["patches"][0]["FN"] - 1.0))
        for k in counts:
            counts[k] += r.extra["balance"][k]
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return dict(kind="mbench", cases=len(cases), quick=quick, wall_s=wall, cpu_s=cpu, load=la,
                max_FN_error=max(errs), **counts)


def startup() -> dict:
    """Start-up: ``-X importtime`` of ``import conformal`` (its cumulative line), and the best of 5
    wall times of a process importing the package less that of an empty process."""
    p = subprocess.run([sys.executable, "-X", "importtime", "-c", "import conformal"], capture_output=True,
                       text=True, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)})
    us = [int(ln.split("|")[1]) for ln in p.stderr.splitlines() if ln.rstrip().endswith("| conformal")]

    def best(code):
        walls = []
        for _ in range(5):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)})
            walls.append(time.perf_counter() - t0)
        return min(walls)

    la = load()
    return dict(importtime_s=(us[-1] * 1e-6 if us else None), process_s=best("import conformal") - best("pass"),
                load=la, target_s=IMPORT_TARGET_S)


def small_solve_process() -> dict:
    """``conformal solve`` of case circ (n = 50, steady rolling) with the exact theory as its own
    process: CONTACT's 0.29 s (GDsteady) is its whole program run too."""
    cmd = [sys.executable, "-m", "conformal.cli", "solve", str(SCENES / "circ.toml"), "--theory", "exact"]
    r = timed_command(cmd, 3, ROOT, timeout=120)
    r["contact_s"] = CONTACT["gdsteady_s"][50]
    return r


def perfc_case(path: Path = PERFC_SHIFT) -> dict:
    """CONTACT's shift performance deck (module 3, one case): the numbers the job needs, read from
    the lines CONTACT's input format fixes for this deck (PEN CKSI CETA CPHI; FSTAT FKIN; POISS GG;
    MX MY XL YL DX DY; IBASE = 2: NN XM RM Y1 DY1 and the NN heights B(k)), and the undeformed
    distance of IBASE = 2, h = B(y) (linear between the points) + (x - XM)^2 / (2 RM) (CONTACT's
    m_sdis.f90).  Returns grid, h, approach, xi, eta, phi (the rigid shift, mm and rad), mu, material
    and eps (CONTACT's tolerance)."""
    from conformal.grid import PlanarGrid
    from conformal.materials import Material

    lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.lstrip().startswith("%")]

    def numbers(tag: str, k: int, after: int = 0) -> list[float]:
        i = next(j for j, ln in enumerate(lines) if tag in ln)
        return [float(v) for v in lines[i + after].split()[:k]]

    pen, cksi, ceta, cphi = numbers("PEN, CKSI", 4)
    fstat, fkin = numbers("FSTAT, FKIN", 2)
    nu1, nu2, g1, g2 = numbers("POISS 1,2", 4)
    eps = numbers("MAXGS", 5)[4]
    mx, my, xl, yl, dx, dy = numbers("MX,MY,XL,YL,DX,DY", 6)
    nn, xm, rm, y1, dy1 = numbers("NN, XM", 5)
    i = next(j for j, ln in enumerate(lines) if "NN, XM" in ln) + 1
    b: list[float] = []
    while len(b) < int(nn):
        b += [float(v) for v in lines[i].split()]
        i += 1
    grid = PlanarGrid(int(mx), int(my), dx, dy, xl, yl)
    X, Y = grid.mesh()
    h = np.interp(Y, y1 + dy1 * np.arange(int(nn)), np.array(b[:int(nn)])) + (X - xm) ** 2 / (2.0 * rm)
    if fstat != fkin:
        raise ValueError(f"{path.name}: static and kinetic friction differ")
    return dict(grid=grid, h=h, approach=pen, xi=cksi, eta=ceta, phi=cphi, mu=fstat,
                material=Material(G1=g1, nu1=nu1, G2=g2, nu2=nu2), eps=eps)


def perfc_shift(repeats: int, path: Path = PERFC_SHIFT) -> dict:
    """CONTACT's shift performance case solved as CONTACT runs it: the influence numbers, the normal
    problem with the approach prescribed, then the shift (T = 1) from zero tractions, both to the
    deck's tolerance (1e-7), in this process; CPU and wall seconds, best and median of ``repeats``
    (CONTACT's 0.13 s is its whole program), with the contact and slip element counts and the
    forces (CONTACT's counts: ``CONTACT["perfc_ncon"]``, ``["perfc_nslip"]``)."""
    from conformal.influence.halfspace import HalfSpaceInfluence
    from conformal.solvers import tangential as tang
    from conformal.solvers.normal import solve_normal

    c = perfc_case(path)
    g = c["grid"]
    la = load()
    runs = []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        op = HalfSpaceInfluence.for_grid(g.mx, g.my, g.dx, g.dy, c["material"], shared=False)
        ns = solve_normal(op, g, c["h"], approach=c["approach"], tol=c["eps"])
        t1, c1 = time.perf_counter(), time.process_time()
        ts = tang.solve_tangential(op, g, ns.pn, xi=c["xi"], eta=c["eta"], phi=c["phi"], mu_static=c["mu"],
                                   mu_kinetic=c["mu"], rolling="shift", tol=c["eps"])
        t2, c2 = time.perf_counter(), time.process_time()
        runs.append((t2 - t0, c2 - c0, t1 - t0, c1 - c0, t2 - t1, c2 - c1))
    r = np.array(runs)
    names = ("wall_s", "cpu_s", "normal_wall_s", "normal_cpu_s", "shift_wall_s", "shift_cpu_s")
    out = dict(kind="perfc_shift", deck=path.name, grid=[g.mx, g.my], repeats=repeats, load=la,
               n_contact=int(ns.n_contact), n_slip=int(np.count_nonzero(ts.status == 2)),
               FN=float(ns.FN), FX=float(ts.px.sum() * g.area), FY=float(ts.py.sum() * g.area),
               normal_iterations=int(ns.iterations), newton_iterations=int(ts.iterations),
               products=int(ts.products), coarse_products=float(ts.coarse_products), converged=bool(ts.converged))
    for k, name in enumerate(names):
        out[name] = float(r[:, k].min())
        out[name.replace("_s", "_median_s")] = float(np.median(r[:, k]))
    return out


def contact_ratios(res: dict) -> list[dict]:
    """Every measured job as a ratio to CONTACT's time for it (< 1: faster than CONTACT)."""
    out = []
    for r in res.get("mbench", []):
        if r.get("quick") is False and "error" not in r:
            out.append(dict(job="Manchester A-2.2 right wheel, 21 shifts, one process",
                            ours_s=r["wall_s"], cpu_s=r["cpu_s"], contact_s=CONTACT["mbench_right_s"],
                            source=CONTACT["mbench_source"], load=r["load"]))
    for h in res.get("halfspace", []):
        n = h["n"]
        if n in CONTACT["normal_s"]:
            out.append(dict(job=f"normal problem, circ {n}^2", ours_s=h["normal_wall_s"], contact_s=CONTACT["normal_s"][n],
                            source=CONTACT["circ_source"], load=h["load"]))
        if n in CONTACT["gdsteady_s"]:
            out.append(dict(job=f"steady rolling, circ {n}^2 (GDsteady)", ours_s=h["steady_wall_s"],
                            contact_s=CONTACT["gdsteady_s"][n], source=CONTACT["circ_source"], load=h["load"]))
    pc = res.get("perfc_shift")
    if pc:
        out.append(dict(job=f"shift (T = 1), CONTACT's case {pc['grid'][0]} x {pc['grid'][1]}: influence numbers, "
                            "normal problem and shift", ours_s=pc["wall_s"], cpu_s=pc["cpu_s"],
                        contact_s=CONTACT["perfc_shift_s"], source=CONTACT["perfc_source"], load=pc["load"]))
        out.append(dict(job="... its shift alone (CONTACT: whole run less its normal-only run)", ours_s=pc["shift_wall_s"],
                        cpu_s=pc["shift_cpu_s"], contact_s=CONTACT["perfc_shift_s"] - CONTACT["perfc_normal_s"],
                        source=CONTACT["perfc_source"], load=pc["load"]))
    sp = res.get("small_solve")
    if sp:
        out.append(dict(job="`conformal solve` circ 50^2 steady rolling, as a process", ours_s=sp["wall_s"],
                        cpu_s=sp["cpu_s"], contact_s=sp["contact_s"], source=CONTACT["circ_source"], load=sp["load"]))
    for r in out:
        r["ratio"] = r["ours_s"] / r["contact_s"]
        # CONTACT's times are whole-program wall times on a quiet machine, where wall ~ CPU: on a
        # loaded machine our CPU time is the fairer numerator
        r["cpu_ratio"] = r["cpu_s"] / r["contact_s"] if r.get("cpu_s") else None
    return out


# ----------------------------------------------------------------------------- report
def _f(v, fmt=".2f", none="-"):
    return none if v is None else format(v, fmt)


def report(res: dict, out: Path) -> str:
    T = TARGETS
    L = ["# Performance of the pipeline (studies/performance.py)", "",
         f"Machine: {os.cpu_count()} cores; load average (1 min) when each wall time was taken in its "
         "row; CPU seconds where given are less sensitive to the load.  Targets: issue 13.", ""]
    hs = res.get("halfspace", [])
    if hs:
        L += ["## Steady rolling and the normal problem (case circ)", "",
              "| n | products | + nested start | Newton its | steady wall s | steady FFT pairs | normal its | "
              "normal wall s | normal FFT pairs | FFT pair ms | load |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for r in hs:
            L.append(f"| {r['n']} | {r['products']} | {r['coarse_products']:.1f} | {r['newton_iterations']} | "
                     f"{r['steady_wall_s']:.3f} | {r['steady_fft_pairs']:.0f} | {r['normal_iterations']} | "
                     f"{r['normal_wall_s']:.3f} | {r['normal_fft_pairs']:.0f} | {1e3 * r['fft_pair_s']:.2f} | {r['load']:.1f} |")
        g = res.get("growth", {})
        L += ["", f"Growth with N = n^2 over n = {g.get('sizes')}: products (+ nested start) N^"
              f"{_f(g.get('products'))}, wall N^{_f(g.get('wall'))} (target N^{T['growth']}); target at "
              f"n = 200: <= {T['fft_pairs_200']} FFT pairs.", ""]
    for r in res.get("fe_pair", []):
        L += [f"## FE influence numbers, wheel + rail, {r['mx']} x {r['ms']} grid of 0.4 mm, first time "
              f"({r['workers']} process{'es' if r['workers'] > 1 else ''})", ""]
        if "error" in r:
            L += [f"failed: {r['error']}", ""]
            continue
        L += [f"Wall **{r['wall_s']:.1f} s** (target {T['fe_51x39_s']:g} s at 51 x 39), CPU {r['cpu_s']:.1f} s, "
              f"peak {r['peak_gib']:.2f} GiB per process, load {r['load']:.1f}.", "",
              "| body | unknowns | mesh s | assemble s | rhs s | factor s | solve s | observe s | total s | peak GiB |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for b in ("rail", "wheel"):
            s = r[b]
            L.append(f"| {b} | {s['dofs']} | " + " | ".join(_f(s[k], ".1f") for k in
                     ("mesh_s", "assemble_s", "rhs_s", "factor_s", "solve_s", "observe_s", "total_s"))
                     + f" | {_f(s['peak_rss_gib'])} |")
        L.append("")
    if res.get("fe_scenes"):
        L += ["## Example FE scenes, first solve (empty cache)", "",
              f"Targets: <= {T['fe_scene_s']:g} s and <= {T['fe_scene_gib']:g} GiB.", "",
              "| scene | wall s | CPU s | peak GiB (process / child) | FE bodies: total s (unknowns) | FN | load |",
              "|---|---:|---:|---:|---|---:|---:|"]
        for r in res["fe_scenes"]:
            name = r["scene"] + (" (influence fe)" if r.get("influence_fe_override") else "")
            if "error" in r:
                L.append(f"| {name} | failed: {r['error']} | | | | | |")
                continue
            bodies = "; ".join(f"{k} " + ", ".join(f"{b['total_s']:.1f} ({b['dofs']})" for b in v)
                               for k, v in r["fe_bodies"].items())
            L.append(f"| {name} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['peak_gib_self']:.2f} / "
                     f"{r['peak_gib_child']:.2f} | {bodies} | {r['FN']:.0f} | {r['load']:.1f} |")
        L.append("")
    for key, title, target in (("demo", "`conformal demo`", T["demo_s"]), ("tests", "README test command", T["tests_s"])):
        r = res.get(key)
        if r:
            L += [f"## {title}", "", f"`{r['command']}`: best wall **{r['wall_s']:.1f} s** of {len(r['walls'])} "
                  f"(all: {', '.join(f'{w:.1f}' for w in r['walls'])}), CPU {r['cpu_s']:.1f} s (all processes), "
                  f"load {r['load']:.1f}, exit {r['rc']}; target {target:g} s.", ""]
    ratios = res.get("contact_ratios") or []
    if ratios or res.get("startup") or res.get("mbench"):
        L += ["## Against CONTACT (issue 23)", "",
              "Ratio = our wall time / CONTACT's for the same job (< 1: faster); CONTACT's times are stored in "
              "`studies/performance.py` (`CONTACT`) with their source; ratio (CPU) = our CPU time / CONTACT's "
              "(quiet-machine) time, the fairer figure when the load average exceeds the 2 cores.", "",
              "| job | ours s | CONTACT s | ratio | ratio (CPU) | source of CONTACT's time | load |",
              "|---|---:|---:|---:|---:|---|---:|"]
        for r in ratios:
            L.append(f"| {r['job']} | {r['ours_s']:.3f}" + (f" (CPU {r['cpu_s']:.2f})" if r.get("cpu_s") else "")
                     + f" | {r['contact_s']:.3f} | **{r['ratio']:.2f}** | {_f(r.get('cpu_ratio'))} | {r['source']} "
                     f"| {r['load']:.1f} |")
        L.append("")
        for r in res.get("mbench", []):
            if "error" in r:
                L += [f"Manchester sequence failed: {r['error']}", ""]
                continue
            L += [f"Manchester A-2.2 right wheel, {r['cases']} cases{' (quick: 0.4 mm elements)' if r['quick'] else ''}"
                  f": {r['wall_s']:.2f} s wall, "
                  f"{r['cpu_s']:.2f} s CPU (load {r['load']:.1f}); {r['searches']} geometry searches, "
                  f"{r['normal_solves']} normal solves in the balance, {r['tangential_solves']} contact solves; "
                  f"largest FN error against CONTACT {100 * r['max_FN_error']:.2f} % (target: 1 %, and <= "
                  f"{0.5 * CONTACT['mbench_right_s']:.3f} s on a quiet machine).", ""]
            if r.get("first_cpu_s_all"):
                L += [f"In {len(r['first_cpu_s_all'])} fresh processes (the row: the median): first run "
                      + " / ".join(f"{x:.2f}" for x in r["first_cpu_s_all"]) + " s CPU"
                      + (("; the second run in the same process (caches warm) "
                          + " / ".join(f"{x:.2f}" for x in r["warm_cpu_s_all"]) + " s") if r.get("warm_cpu_s_all") else "")
                      + f"; CONTACT {CONTACT['mbench_right_s']:.2f} s.", ""]
        pc = res.get("perfc_shift")
        if pc:
            L += [f"CONTACT's shift performance case ({pc['deck']}, {pc['grid'][0]} x {pc['grid'][1]} elements, the "
                  f"deck's tolerance): {pc['n_contact']} contact and {pc['n_slip']} slip elements (CONTACT "
                  f"{CONTACT['perfc_ncon']} and {CONTACT['perfc_nslip']}), FN {pc['FN']:.0f} N, FX {pc['FX']:.1f} N, "
                  f"FY {pc['FY']:.1f} N; best of {pc['repeats']}: {pc['cpu_s']:.3f} s CPU (median "
                  f"{pc['cpu_median_s']:.3f}), of which the normal problem {pc['normal_cpu_s']:.3f} s "
                  f"({pc['normal_iterations']} iterations) and the shift {pc['shift_cpu_s']:.3f} s "
                  f"({pc['newton_iterations']} Newton steps, {pc['products']} + {pc['coarse_products']:.1f} "
                  f"products); CONTACT {CONTACT['perfc_shift_s']} s whole program, "
                  f"{CONTACT['perfc_normal_s']} s for the normal problem alone.", ""]
        st = res.get("startup")
        if st:
            L += [f"Start-up: `python -X importtime -c \"import conformal\"` {_f(st['importtime_s'], '.3f')} s for the "
                  f"package; a process importing it {st['process_s']:.3f} s more than an empty process (load "
                  f"{st['load']:.1f}); target {st['target_s']:g} s.", ""]
        g = res.get("growth_200_400")
        if g is not None:
            L += [f"Steady rolling growth from 200^2 to 400^2: N^{g:.2f} (CONTACT's GDsteady N^"
                  f"{CONTACT['gdsteady_growth_200_400']}, {CONTACT['growth_source']}; target N^1.15).", ""]
    text = "\n".join(L) + "\n"
    out.mkdir(parents=True, exist_ok=True)
    (out / "performance.md").write_text(text, encoding="utf-8")
    (out / "performance.json").write_text(json.dumps(res, indent=1, default=str) + "\n", encoding="utf-8")
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, one small FE case (for the test)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 200, 300, 400])
    ap.add_argument("--repeats", type=int, default=3, help="repeats of the half-space solves and the demo (best)")
    ap.add_argument("--sequential", action="store_true", help="also the FE pair in one process")
    ap.add_argument("--worn", action="store_true", help="also the worn three-patch scene with FE numbers")
    ap.add_argument("--tests", action="store_true", help="also time the README's test command")
    ap.add_argument("--no-demo", action="store_true")
    ap.add_argument("--no-fe", action="store_true", help="leave out the FE numbers and the FE scenes")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--one", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        what = json.loads(args.one)
        if what["kind"] == "mbench":   # the first run in a fresh process, and a second (caches warm)
            r = mbench_sequence(what["quick"])
            if what.get("again"):
                r["warm_cpu_s"] = mbench_sequence(what["quick"])["cpu_s"]
            print(json.dumps(r, default=str))
            return 0
        if what["kind"] == "perfc_shift":   # one run in a fresh process (studies/contact_side_by_side.py)
            print(json.dumps(perfc_shift(1), default=str))
            return 0
        r = fe_pair(what["mx"], what["ms"], what["workers"]) if what["kind"] == "pair" else \
            fe_scene(what["scene"], what.get("influence_fe", False))
        print(json.dumps(r, default=str))
        return 0
    if args.quick:
        args.sizes, args.repeats = [25, 50, 100], 1
    res: dict = {"quick": bool(args.quick), "cpu_count": os.cpu_count(), "load_start": load()}
    rows = halfspace_rows(sorted(args.sizes), args.repeats)
    big = [r for r in rows if r["n"] >= 50]
    res["halfspace"] = rows
    res["growth"] = {"sizes": [r["n"] for r in big], "products": growth([r["n"] for r in big], [r["cost_products"] for r in big]),
                     "wall": growth([r["n"] for r in big], [r["steady_wall_s"] for r in big])}
    sz = {r["n"]: r["steady_wall_s"] for r in rows}
    if 200 in sz and 400 in sz:
        res["growth_200_400"] = growth([200, 400], [sz[200], sz[400]])
    # the sequence in MBENCH_PROCESSES fresh processes (the machine's speed varies by about +-25 %
    # from minute to minute): the row is the process with the median first run, all are kept
    runs = [spawn({"kind": "mbench", "quick": bool(args.quick), "again": not args.quick}, timeout=1200)
            for _ in range(1 if args.quick else MBENCH_PROCESSES)]
    ok = sorted((x for x in runs if "error" not in x), key=lambda x: x["cpu_s"])
    r = ok[len(ok) // 2] if ok else runs[0]
    if ok:
        r["first_cpu_s_all"] = [x["cpu_s"] for x in ok]
        r["warm_cpu_s_all"] = [x["warm_cpu_s"] for x in ok if "warm_cpu_s" in x]
    res["mbench"] = [r]
    print("[mbench] " + (r.get("error") or f"{r['wall_s']:.2f} s wall, {r['cpu_s']:.2f} s CPU, max FN error "
                         f"{100 * r['max_FN_error']:.2f} %"), flush=True)
    res["startup"] = startup()
    print(f"[startup] importtime {res['startup']['importtime_s']} s, process {res['startup']['process_s']:.3f} s",
          flush=True)
    res["perfc_shift"] = perfc_shift(3 if args.quick else 7)
    pc = res["perfc_shift"]
    print(f"[perfc shift] {pc['cpu_s']:.3f} s CPU ({pc['shift_cpu_s']:.3f} s the shift), {pc['n_contact']} contact "
          f"and {pc['n_slip']} slip elements (CONTACT {CONTACT['perfc_ncon']}, {CONTACT['perfc_nslip']})", flush=True)
    res["small_solve"] = small_solve_process()
    print(f"[small solve] {res['small_solve']['wall_s']:.2f} s", flush=True)
    res["contact_ratios"] = contact_ratios(res)
    mx, ms = (21, 15) if args.quick else (51, 39)
    res["fe_pair"] = []
    for workers in ([] if args.no_fe else [2, 1] if args.sequential else [2]):
        r = spawn({"kind": "pair", "mx": mx, "ms": ms, "workers": workers}, timeout=900)
        res["fe_pair"].append(r)
        print(f"[fe] {mx} x {ms}, {workers} process(es): " + (r.get("error") or f"{r['wall_s']:.1f} s wall, "
              f"{r['cpu_s']:.1f} s CPU, {r['peak_gib']:.2f} GiB"), flush=True)
    res["fe_scenes"] = []
    for path in ([] if args.no_fe else fe_scenes(args.quick, args.worn)):
        cache = tempfile.mkdtemp(prefix="conformal_perf_cache_")
        try:
            worn = Path(path).name == WORN
            r = spawn({"kind": "scene", "scene": path, "influence_fe": worn}, timeout=1800,
                      env={"CONFORMAL_CACHE": cache})
        finally:
            shutil.rmtree(cache, ignore_errors=True)
        res["fe_scenes"].append(r)
        print(f"[scene] {Path(path).name}: " + (r.get("error") or f"{r['wall_s']:.1f} s, "
              f"{max(r['peak_gib_self'], r['peak_gib_child']):.2f} GiB"), flush=True)
    if not args.no_demo:
        with tempfile.TemporaryDirectory() as tmp:
            res["demo"] = timed_command(demo_command(), args.repeats, Path(tmp), timeout=300)
        print(f"[demo] {res['demo']['wall_s']:.2f} s", flush=True)
    if args.tests:
        res["tests"] = timed_command([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"], 1, ROOT,
                                     timeout=3600)
        print(f"[tests] {res['tests']['wall_s']:.0f} s", flush=True)
    res["load_end"] = load()
    print(report(res, args.out))
    write_sidecar(args.out, __file__, args, extra={"load_start": res["load_start"], "load_end": res["load_end"]})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
