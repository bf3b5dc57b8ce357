"""Creep-force tables (conformal.tables): normalisation, build (serial, process pool, Dask),
resumption, file integrity, evaluator, the "table" model, and the shipped table against direct
exact solves.  Tiny tables are built here (a few dozen nodes on coarse grids)."""
from __future__ import annotations

import json
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from conformal.cli import main
from conformal.errors import ConformalError, InputError
from conformal.tables import TableSpec, build_table, evaluate, load_table, spec_from_dict
from conformal.tables import build as tbuild
from conformal.tables.spec import creepages_of_node, polar, saturation_scales
from conformal.tables.table import CreepTable, interpolate, save_table
from conformal.theories.coefficients import coefficient_arrays
from _paths import REFERENCE, ROOT

G, NU, MU, FN, A = 82000.0, 0.28, 0.4, 5.0e4, 6.0
TINY = dict(ratio_min=1.0, ratio_max=1.0, n_ratio=1, nu_min=NU, nu_max=NU, n_nu=1, rho_max=20.0, n_rho=3,
            n_theta=2, spin_max=1.0, n_spin=3, grid_n=12, chunk=4)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("tables") / "tiny.npz"
    rep = build_table(TableSpec(**TINY), out, progress=False)
    assert rep.solved == 5 and not rep.failed
    return load_table(out)


def _scene(xi, eta, phi, theory="exact", **model):
    from conformal.scene import scene_from_dict

    return scene_from_dict({"material": {"G": G, "nu": NU}, "friction": {"mu": MU},
                            "geometry": {"kind": "hertz", "a": A, "b": A}, "load": {"normal_force": FN},
                            "kinematics": {"xi": xi, "eta": eta, "phi": phi}, "grid": {"n": 12},
                            "model": {"theory": theory, **model}})


def _creepages_at(nx, ny, nphi):
    """Dimensional creepages of the 6 mm circle at normalised (nx, ny, nphi) of Eq. T1."""
    c = [float(np.asarray(v)) for v in coefficient_arrays(1.0, NU)]
    kx, ky, kp = (float(k) for k in saturation_scales(A, A, FN, MU, G, *c))
    return nx / kx, ny / ky, nphi / kp


# ----------------------------------------------------------------------------- spec
def test_spec_rejects_unknown_keys_naming_the_closest():
    with pytest.raises(InputError, match="did you mean 'rho_max'"):
        spec_from_dict({"table": {"rho_mx": 3}})
    with pytest.raises(InputError, match=r"\[solvr\].*did you mean 'solver'"):
        spec_from_dict({"solvr": {"grid_n": 10}})
    with pytest.raises(InputError, match="n_spin"):
        spec_from_dict({"table": {"n_spin": 4}})
    with pytest.raises(InputError, match="ratio_min"):
        spec_from_dict({"table": {"ratio_min": 2.0, "ratio_max": 1.0}})
    s = spec_from_dict({"table": {"rho_max": 3, "n_rho": 5}, "solver": {"grid_n": 16}})
    assert s.rho_max == 3.0 and s.n_rho == 5 and s.grid_n == 16


def test_symmetry_reduction_and_node_inverse():
    """polar (Eqs. T3-T4) inverts creepages_of_node, and folds every octant onto nx, ny >= 0."""
    s, th, q = 0.4, 0.3, -0.25
    nx, ny, nphi = creepages_of_node(s, th, q)
    assert np.allclose(polar(nx, ny, nphi)[:3], (s, th, q), atol=1e-14)
    for sx, sy in ((1, 1), (-1, 1), (1, -1), (-1, -1)):
        # (sx nx, sy ny, sy nphi) folds back onto (nx, ny, nphi): reversal when sx < 0, then a mirror
        s2, th2, q2, sa, sg = polar(sx * nx, sy * ny, sy * nphi)
        assert np.allclose((s2, th2, q2), (s, th, q), atol=1e-14)
        assert (float(sa), float(sg)) == (sx, sx * sy)


# ----------------------------------------------------------------------------- node values
def test_node_values_equal_direct_exact_solves_at_another_scale(tiny):
    """A table built at ab = 1 mm², G, mu, FN of build.py reproduces a direct exact solve of a
    6 mm circle with other mu and FN at the nodes (dimensional analysis of Eqs. T1-T2)."""
    from conformal.dispatch import solve_scene

    for s, th, q in ((tiny.spec.s_max / 2, 0.0, 0.0), (tiny.spec.s_max / 2, math.pi / 2, tiny.spec.q_max),
                     (tiny.spec.s_max / 2, 0.0, -tiny.spec.q_max)):
        xi, eta, phi = _creepages_at(*creepages_of_node(s, th, q))
        r = solve_scene(_scene(xi, eta, phi))
        FX, FY, MZ = evaluate(tiny, A, A, r.FN, MU, G, NU, xi, eta, phi)
        assert abs(FX - r.FX) / (MU * r.FN) < 2e-5 and abs(FY - r.FY) / (MU * r.FN) < 2e-5
        assert abs(MZ - r.MZ) / (MU * r.FN * A) < 2e-5


def test_symmetries_against_exact_solves(tiny):
    """Reversed and mirrored creepages (Eq. T3) against exact solves of those problems."""
    from conformal.dispatch import solve_scene

    xi, eta, phi = _creepages_at(*creepages_of_node(tiny.spec.s_max / 2, math.pi / 2, tiny.spec.q_max))
    for sx, sy in ((-1, -1), (1, -1)):
        args = (-xi, -eta, -phi) if sx < 0 else (xi, -eta, -phi)
        r = solve_scene(_scene(*args))
        FX, FY, MZ = evaluate(tiny, A, A, r.FN, MU, G, NU, *args)
        assert np.allclose([FX, FY, MZ / A], [r.FX, r.FY, r.MZ / A], atol=2e-5 * MU * r.FN)


def test_saturation_and_rest(tiny):
    """Zero creepage: no force; rho = 20 (20 x saturation, pure xi): full sliding, F = -mu FN."""
    f0 = interpolate(tiny, 0.0, NU, 0.0, 0.0, 0.0)[0]
    assert np.allclose(f0, 0.0, atol=1e-9)
    f = interpolate(tiny, 0.0, NU, tiny.spec.s_max, 0.0, 0.0)[0]
    assert abs(f[0] + 1.0) < 2e-3 and abs(f[1]) < 1e-8


# ----------------------------------------------------------------------------- evaluator
def _analytic_table(fun, **kw):
    spec = TableSpec(**{**TINY, **dict(ratio_min=0.5, ratio_max=2.0, n_ratio=4, nu_min=0.2, nu_max=0.3, n_nu=2,
                                       n_rho=5, n_theta=4, n_spin=5), **kw})
    grids = np.meshgrid(*spec.axes(), indexing="ij")
    vals = np.stack(fun(*grids), axis=-1)
    c = np.ones(spec.shape[:2])
    return CreepTable(spec, vals, c * 4.0, c * 3.5, c * 1.5, {"spec": spec.to_dict()})


def test_interpolation_reproduces_nodes_and_polynomials():
    """The evaluator (Eq. T5) is exact (to float32) at the nodes and for functions cubic along
    ln(a/b) anywhere (cubic Hermite with the not-a-knot spline's slopes: the spline itself, which
    reproduces cubics), along s linear for the forces (PCHIP) and cubic for mz (spline), cubic
    along theta and quadratic along q (Akima's slopes reproduce quadratics on a uniform axis) at
    the fine grid's nodes, and linear in nu anywhere."""
    def fun(t, nu, s, th, q):
        return (t**3 - 2 * t + nu * s, 0.5 * th**3 - q**2 + nu, s**3 * q**2 + t**3 * nu)

    from conformal.tables.table import eval_grid

    tab = _analytic_table(fun, n_spin=7)
    pts = [np.ravel(g) for g in np.meshgrid(*tab.spec.axes(), indexing="ij")]
    assert np.allclose(interpolate(tab, *pts), np.stack(fun(*pts), 1), atol=2e-6)
    rng = np.random.default_rng(3)
    fine = eval_grid(tab).axes
    # s, theta, q on the fine grid's nodes (read linearly between them); ln(a/b) and nu anywhere
    s, th, q = (ax[rng.integers(0, ax.size, 500)] for ax in (fine[2], fine[3], fine[4]))
    t = rng.uniform(fine[0][0], fine[0][-1], 500)
    nu = rng.uniform(0.2, 0.3, 500)
    ref = np.stack(fun(t, nu, s, th, q), 1)
    assert np.allclose(interpolate(tab, t, nu, s, th, q), ref, atol=5e-6)
    # between the fine nodes of a linear function: exact as well (multilinear read)
    lin = _analytic_table(lambda t, nu, s, th, q: (s + 2 * th - q, nu * q, t + th))
    x = [rng.uniform(ax[0], ax[-1], 500) for ax in lin.spec.axes()]
    assert np.allclose(interpolate(lin, *x), np.stack([x[2] + 2 * x[3] - x[4], x[1] * x[4], x[0] + x[3]], 1),
                       atol=2e-6)


def test_force_does_not_overshoot_the_knee_of_full_slip():
    """Along s the force bends sharply where the contact reaches full slip and then stays at mu FN:
    the monotone cubic (PCHIP) keeps the interpolant between the node values (a not-a-knot spline
    overshot the shipped table's knee by 0.013 of mu FN; measured at a/b = 3.4)."""
    from conformal.tables.table import eval_grid

    knee = 0.55
    tab = _analytic_table(lambda t, nu, s, th, q: (-np.minimum(s / knee, 1.0) + 0 * t, 0 * s, 0 * s), n_rho=9)
    s = eval_grid(tab).axes[2]
    f = interpolate(tab, np.zeros_like(s), np.full_like(s, 0.25), s, np.zeros_like(s), np.zeros_like(s))[:, 0]
    assert f.min() >= -1.0 - 1e-6 and np.all(np.diff(f) <= 1e-6)      # monotone, never below -1
    spline = _analytic_table(lambda t, nu, s, th, q: (0 * s, 0 * s, -np.minimum(s / knee, 1.0) + 0 * t), n_rho=9)
    m = interpolate(spline, np.zeros_like(s), np.full_like(s, 0.25), s, np.zeros_like(s), np.zeros_like(s))[:, 2]
    assert m.min() < -1.0 - 1e-3          # the spline (still used for mz) does overshoot such a knee


def test_akima_along_spin_does_not_ring_past_a_ridge():
    """A corner in the spin direction (the force's ridge where spin opposes the lateral creepage):
    Akima's slopes (Akima 1970) keep the cells beyond the corner's neighbours exact, where a
    not-a-knot spline through the same nodes rings.  f = max(q - q0, 0) with q0 inside a cell."""
    from scipy.interpolate import CubicSpline

    q0 = 0.01
    tab = _analytic_table(lambda t, nu, s, th, q: (np.maximum(q - q0, 0.0), 0 * q, 0 * q), n_spin=11)
    qn = tab.spec.axes()[4]
    h = qn[1] - qn[0]
    q = np.linspace(qn[0], qn[-1], 801)
    far = np.abs(q - q0) > 2.5 * h          # beyond the corner's cell and its neighbours
    z = np.zeros_like(q)
    f = interpolate(tab, z, z + 0.25, z + 0.1, z + 0.3, q)[:, 0]
    exact = np.maximum(q - q0, 0.0)
    assert np.abs(f - exact)[far].max() < 2e-6
    spline = CubicSpline(qn, np.maximum(qn - q0, 0.0))(q)
    assert np.abs(spline - exact)[far].max() > 1e-4


def test_outside_the_range_is_never_silent(tiny):
    args = (A, A, FN, MU, G, NU)
    with pytest.raises(InputError, match="a/b"):
        evaluate(tiny, 7.0, 6.0, FN, MU, G, NU, 1e-4, 0.0, 0.0)
    with pytest.raises(InputError, match="nu"):
        evaluate(tiny, A, A, FN, MU, G, 0.3, 1e-4, 0.0, 0.0)
    xi_big = _creepages_at(25.0, 0.0, 0.0)[0]
    with pytest.raises(InputError, match="rho"):
        evaluate(tiny, *args, xi_big, 0.0, 0.0)
    with pytest.warns(RuntimeWarning, match="NaN returned"):
        FX, _, _ = evaluate(tiny, *args, [1e-4, xi_big], 0.0, 0.0, outside="nan")
    assert np.isfinite(FX[0]) and np.isnan(FX[1])
    with pytest.warns(RuntimeWarning, match="clamped"):
        FX, _, _ = evaluate(tiny, *args, xi_big, 0.0, 0.0, outside="clamp")
    edge = evaluate(tiny, *args, _creepages_at(20.0, 0.0, 0.0)[0], 0.0, 0.0)[0]
    assert math.isclose(float(FX), float(edge), rel_tol=1e-12)
    for bad in (dict(FN=-1.0), dict(mu=0.0), dict(xi=math.nan)):
        kw = {**dict(a=A, b=A, FN=FN, mu=MU, G=G, nu=NU, xi=1e-4, eta=0.0, phi=0.0), **bad}
        with pytest.raises(InputError):
            evaluate(tiny, **kw)


def _assert_edit_detected(path, key: str, tmp_path) -> None:
    """A copy of the table file with ``key`` scaled by 1.001 is refused (content hash)."""
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data[key] = data[key] * 1.001
    np.savez(tmp_path / "edited.npz", **data)
    with pytest.raises(InputError, match="content hash"):
        load_table(tmp_path / "edited.npz")


def test_file_integrity(tiny, tmp_path):
    p = save_table(tiny, tmp_path / "t.npz")
    assert load_table(p).content_hash == tiny.content_hash
    _assert_edit_detected(p, "values", tmp_path)
    (tmp_path / "junk.npz").write_bytes(b"not a table")
    with pytest.raises(InputError, match="cannot read"):
        load_table(tmp_path / "junk.npz")
    with pytest.raises(InputError, match="not found"):
        load_table(tmp_path / "missing.npz")


def test_throughput_vectorised():
    """>= 1e6 contacts per CPU second on the shipped table with nu varying in the batch, one
    thread; the floor asserted here is lower to stay robust on a busy machine
    (studies/creep_table_scaling.py reports the measured rate)."""
    from threadpoolctl import threadpool_limits

    t = load_table()
    rng = np.random.default_rng(0)
    n = 200_000
    a = rng.uniform(4, 8, n)
    b = a / rng.uniform(0.5, 2.0, n)
    xi, eta, phi = rng.uniform(-2e-3, 2e-3, (3, n))
    nu = rng.uniform(0.25, 0.30, n)
    evaluate(t, a, b, 1e5, 0.3, G, nu, xi, eta, phi * 1e-2)          # warm (evaluation grid)
    with threadpool_limits(1):
        c0 = time.process_time()
        FX, FY, MZ = evaluate(t, a, b, 1e5, 0.3, G, nu, xi, eta, phi * 1e-2)
        rate = n / max(time.process_time() - c0, 1e-9)
    assert np.all(np.hypot(FX, FY) <= 0.3e5 * 1.01) and rate > 3e5


# ----------------------------------------------------------------------------- build
def test_resume_after_a_failed_chunk(tmp_path, monkeypatch, tiny):
    """A chunk that fails leaves the others on disk; the next run solves only the missing one and
    gives the same table as an uninterrupted build."""
    spec = TableSpec(**TINY)
    out = tmp_path / "r.npz"
    real = tbuild.solve_chunk

    def flaky(chunk):
        if chunk.index == 1:
            raise ConformalError("worker lost")
        return real(chunk)

    monkeypatch.setattr(tbuild, "solve_chunk", flaky)
    rep = build_table(spec, out, progress=False)
    assert rep.failed and rep.path is None and not out.exists()
    assert len(list(tbuild.parts_folder(out, spec).glob("chunk_*.npz"))) == len(tbuild.chunks(spec)) - 1
    monkeypatch.setattr(tbuild, "solve_chunk", real)
    rep = build_table(spec, out, progress=False)
    assert rep.resumed == len(tbuild.chunks(spec)) - 1 and rep.solved == 1 and out.is_file()
    assert not tbuild.parts_folder(out, spec).exists()
    np.testing.assert_allclose(load_table(out).values, tiny.values, rtol=0, atol=1e-12)


@pytest.mark.slow
def test_process_pool_build_equals_serial(tmp_path, tiny):
    rep = build_table(TableSpec(**TINY), tmp_path / "p.npz", workers=2, progress=False)
    assert rep.solved == 5 and not rep.failed
    np.testing.assert_allclose(load_table(tmp_path / "p.npz").values, tiny.values, rtol=0, atol=1e-12)


@pytest.mark.slow
def test_dask_local_cluster_build_equals_serial(tmp_path, tiny):
    """The Dask path (LocalCluster, the code path of a real cluster with an address) - not skipped."""
    import dask.distributed  # noqa: F401 - part of the test extra

    rep = build_table(TableSpec(**TINY), tmp_path / "d.npz", workers=1, scheduler="local", progress=False)
    assert rep.solved == 5 and not rep.failed
    np.testing.assert_allclose(load_table(tmp_path / "d.npz").values, tiny.values, rtol=0, atol=1e-12)


def test_cli_build_info_and_bad_spec(tmp_path, capsys, tiny):
    spec = tmp_path / "spec.toml"
    spec.write_text("[table]\n" + "".join(f"{k} = {v}\n" for k, v in TINY.items()
                                          if k not in ("grid_n", "chunk")) + "[solver]\ngrid_n = 12\n[build]\nchunk = 4\n")
    out = tmp_path / "c.npz"
    assert main(["table", "build", str(spec), "--out", str(out), "--no-progress"]) == 0
    assert "5 solved" in capsys.readouterr().out
    assert main(["table", "info", str(out)]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["content_hash"] == load_table(out).content_hash and info["shape"] == [1, 1, 3, 2, 3]
    assert info["solver"]["grid_n"] == 12 and info["nonconverged_nodes"] == 0
    spec.write_text("[table]\nn_rhoo = 3\n")
    assert main(["table", "build", str(spec), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "did you mean 'n_rho'" in err[0]


def test_refine_adds_exact_nodes_in_a_box(tiny, tmp_path, capsys):
    """``conformal table refine``: extra q nodes in a box are exact solves (to the warm start's
    2e-5), the evaluator passes through them, the rest of the table is unchanged, the patch is
    covered by the content hash, and a bad box is one InputError line (exit 2)."""
    out = tmp_path / "r.npz"
    assert main(["table", "refine", tiny.path, "--out", str(out), "--box", "0:1,1:3,0:2", "--q", "0.2:0.3",
                 "--no-progress"]) == 0
    assert "4 nodes in 1 chunks: 0 already done, 1 solved" in capsys.readouterr().out
    r = load_table(out)
    (p,) = r.patches
    assert p.box == (0, 1, 1, 3, 0, 2) and np.allclose(p.q, [0.25]) and r.info()["patch_nodes"] == 4
    s_ax, th_ax = tiny.spec.axes()[2:4]
    S, TH = np.meshgrid(s_ax[1:3], th_ax, indexing="ij")
    nodes = [creepages_of_node(si, ti, 0.25) for si, ti in zip(S.ravel(), TH.ravel())]
    ref = tbuild.solve_points(1.0, NU, *np.array(nodes).T, grid_n=tiny.spec.grid_n, tol=tiny.spec.tol)
    assert np.allclose(p.values.reshape(-1, 3), ref, atol=2e-5)
    got = interpolate(r, 0.0, NU, S.ravel(), TH.ravel(), np.full(S.size, 0.25))
    assert np.allclose(got, ref, atol=2e-5)
    # at q = 0.25 the unrefined table interpolates (3 q nodes: a parabola) and misses
    assert np.abs(interpolate(tiny, 0.0, NU, S.ravel(), TH.ravel(), np.full(S.size, 0.25)) - ref).max() > 1e-3
    # outside the box (s node 0, all q) and at the table's nodes: unchanged
    x = [np.zeros(5), np.full(5, NU), np.zeros(5), np.zeros(5), np.linspace(-0.5, 0.5, 5)]
    assert np.allclose(interpolate(r, *x), interpolate(tiny, *x), atol=1e-6)
    assert r.content_hash != tiny.content_hash
    _assert_edit_detected(out, "patch0_values", tmp_path)
    assert main(["table", "refine", tiny.path, "--out", str(out), "--box", "0:1,1:9,0:2", "--q", "0.2:0.3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "box" in err[0]


# ----------------------------------------------------------------------------- model and shipped table
def test_scene_theory_table(tiny):
    from conformal.dispatch import solve_scene

    xi, eta, phi = _creepages_at(*creepages_of_node(tiny.spec.s_max / 2, 0.0, tiny.spec.q_max))
    r = solve_scene(_scene(xi, eta, phi, theory="table", table=tiny.path))
    ex = solve_scene(_scene(xi, eta, phi))
    # Hertz FN is the prescribed load; at a node the table reproduces the exact solve
    assert r.theory == "table" and math.isclose(r.FN, FN)
    assert abs(r.FX - ex.FX) / (MU * FN) < 1e-4 and abs(r.FY - ex.FY) / (MU * FN) < 1e-4
    with pytest.raises(InputError, match="prescribed forces"):

        from conformal.problem import problems_from_scene
        from conformal.tables.model import solve

        p = problems_from_scene(_scene(xi, eta, phi, theory="table", table=tiny.path))[0]
        solve(replace(p, kinematics=replace(p.kinematics, fx_rel=0.5)))


def test_scene_table_path_is_relative_to_the_scene_file(tiny, tmp_path, monkeypatch):
    """``[model] table`` in a scene file: a relative path is read from the scene file's folder
    (not the working directory), an absolute path as it is, "default" is the shipped table; a
    missing file is one InputError line naming the key; the path survives Scene.with_ and
    to_dict without being resolved twice."""
    import shutil

    from conformal.scene import load_scene, scene_from_dict
    from conformal.dispatch import solve_scene

    folder = tmp_path / "scenes"
    (folder / "tables").mkdir(parents=True)
    shutil.copy(tiny.path, folder / "tables" / "t.npz")
    xi, eta, phi = _creepages_at(*creepages_of_node(tiny.spec.s_max / 2, 0.0, tiny.spec.q_max))
    text = _scene(xi, eta, phi, theory="table").to_dict()

    def write(name, table):
        lines = []
        for sec, body in text.items():
            if sec == "name":
                continue
            body = dict(body, **({"table": table} if sec == "model" else {}))
            lines.append(f"[{sec}]")
            lines += [f"{k} = {json.dumps(v)}" for k, v in body.items()]
        (folder / name).write_text("\n".join(lines) + "\n")
        return folder / name

    elsewhere = tmp_path / "work"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    scene = load_scene(write("rel.toml", "tables/t.npz"))
    want = str((folder / "tables" / "t.npz").resolve())
    assert scene.model.options["table"] == want
    r = solve_scene(scene)
    assert r.extra["table"] == want and r.extra["table_hash"] == tiny.content_hash[:16]
    again = scene.with_(load__normal_force=2 * FN)
    assert again.model.options["table"] == want and scene_from_dict(scene.to_dict()).model.options["table"] == want
    assert load_scene(write("abs.toml", want)).model.options["table"] == want
    assert load_scene(write("def.toml", "default")).model.options["table"] == "default"
    with pytest.raises(InputError, match=r"\[model\] table: no such file"):
        load_scene(write("missing.toml", "t.npz"))        # not looked up in the working directory
    (elsewhere / "t.npz").write_bytes(b"")                 # ... even where one exists there
    with pytest.raises(InputError, match="no such file"):
        load_scene(write("missing.toml", "t.npz"))


def _reference_points():
    path = REFERENCE / "creep_table_points.csv"
    with path.open(encoding="utf-8") as fh:
        lines = [line for line in fh if not line.startswith("#")]
    return np.genfromtxt(lines, delimiter=",", names=True)


def test_shipped_table_against_stored_exact_solves():
    """The shipped table at the 300 random points of studies/creep_table_accuracy.py (seed 2026)
    against the exact solves stored in tests/reference/creep_table_points.csv: max error of
    F/(mu FN) <= 0.01 and mean <= 0.002 (issue 10's targets).  Measured 0.0034 and 0.00054 (the
    first shipped table, 7 a/b x 9 theta x 23 q nodes with two refinement boxes: 0.0077 and
    0.0011); on 4000 fresh points (the study's hold-out set, seed 18) 0.0054 and 0.00056."""
    d = _reference_points()
    t = load_table()
    s, th, q, sa, sy = polar(d["nx"], d["ny"], d["nphi"])
    f = interpolate(t, np.log(d["a_over_b"]), d["nu"], s, th, q)
    err = np.hypot(sa * f[:, 0] - d["fx_exact"], sa * sy * f[:, 1] - d["fy_exact"])
    assert d.size == 300 and err.max() <= 0.01 and err.mean() <= 0.002, (err.max(), err.mean())
    # through the dimensional evaluator (Eq. T1 with the contact's own coefficients): the same
    a, b = 5.0 * np.sqrt(d["a_over_b"]), 5.0 / np.sqrt(d["a_over_b"])
    kx, ky, kp = saturation_scales(a, b, 1e5, 0.3, G, *coefficient_arrays(d["a_over_b"], d["nu"]))
    FX, FY, _ = evaluate(t, a, b, 1e5, 0.3, G, d["nu"], d["nx"] / kx, d["ny"] / ky, d["nphi"] / kp)
    assert np.allclose(np.stack([FX, FY], 1) / 3e4, np.stack([sa * f[:, 0], sa * sy * f[:, 1]], 1), atol=1e-4)


def test_shipped_table_against_direct_exact_solves():
    """Six fresh random points between the nodes of the shipped table against direct exact solves
    with the table's solver settings (not the points the evaluator was tuned on): measured max
    0.0068, mean 0.0019 of mu FN; bounded by the issue's 0.01 (max) and 0.004 (twice its mean
    target: six points are a small sample)."""
    t = load_table()
    s = t.spec
    rng = np.random.default_rng(11)
    n = 6
    ratio = np.exp(rng.uniform(math.log(s.ratio_min), math.log(s.ratio_max), n))
    nu = rng.uniform(s.nu_min, s.nu_max, n)
    rho = rng.uniform(0.05, 1.5, n)
    th = rng.uniform(0, 2 * math.pi, n)
    nphi = rng.uniform(-1.0, 1.0, n)
    ref = tbuild.solve_points(ratio, nu, rho * np.cos(th), rho * np.sin(th), nphi, grid_n=s.grid_n, tol=s.tol)
    a = 5.0 * np.sqrt(ratio)
    b = 5.0 / np.sqrt(ratio)
    c = coefficient_arrays(ratio, nu)
    kx, ky, kp = saturation_scales(a, b, 1e5, 0.3, G, *c)
    FX, FY, MZ = evaluate(t, a, b, 1e5, 0.3, G, nu, rho * np.cos(th) / kx, rho * np.sin(th) / ky, nphi / kp)
    err = np.hypot(FX / 3e4 - ref[:, 0], FY / 3e4 - ref[:, 1])
    assert err.max() <= 0.01 and err.mean() <= 0.004, err


# ----------------------------------------------------------------------------- studies
def _run_study(name: str, out: Path) -> dict:
    """``python studies/<name>.py --quick --out OUT``: exit 0 and the sidecar run.json."""
    import os
    import subprocess
    import sys

    root = ROOT
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, str(root / "studies" / f"{name}.py"), "--quick", "--out", str(out)],
                       cwd=root, capture_output=True, text=True, timeout=600, env=env)
    assert r.returncode == 0, f"{name} --quick failed:\n{r.stdout[-2000:]}\n{r.stderr[-3000:]}"
    side = json.loads((out / "run.json").read_text())
    assert side["script"] == f"studies/{name}.py" and side["args"]["quick"] is True
    assert Path(side["args"]["out"]) == out
    return side


@pytest.mark.slow
def test_accuracy_study_quick(tmp_path):
    """studies/creep_table_accuracy.py --quick: 20 + 20 hold-out points against exact solves;
    the table's errors are within the issue's bound and FASTSIM's are larger (Kalker's simplified
    theory: several % of mu FN away from the exact one)."""
    _run_study("creep_table_accuracy", tmp_path)
    res = json.loads((tmp_path / "accuracy.json").read_text())
    assert res["quick"] and res["points"] == 20 and res["holdout"]["points"] == 20
    assert res["all_points_table_F"]["max"] <= 0.01
    assert res["fastsim_F"]["mean"] > 5 * res["table_F"]["mean"]
    pts = np.genfromtxt(tmp_path / "accuracy_points.csv", delimiter=",", names=True)
    assert pts.size == 20 and math.isclose(pts["err_table"].max(), res["table_F"]["max"], rel_tol=1e-4)


@pytest.mark.slow
def test_scaling_study_quick(tmp_path):
    """studies/creep_table_scaling.py --quick: every backend (serial, process pool and Dask
    LocalCluster with 1 and 2 workers) builds the same 18-node table; the speed-ups are reported
    with the load they ran under; the evaluator is timed on one thread."""
    side = _run_study("creep_table_scaling", tmp_path)
    res = json.loads((tmp_path / "scaling.json").read_text())
    assert res["quick"] and {(r["backend"], r["workers"]) for r in res["runs"]} == {
        ("serial", 1), ("pool", 1), ("pool", 2), ("dask", 1), ("dask", 2)}
    assert all(r["nodes"] == 18 and r["throughput"] > 0 for r in res["runs"])
    for b in ("pool", "dask"):
        sp = res["speedup"][b]
        assert sp["speedup_2_workers"] > 0 and isinstance(sp["loaded"], bool)
    assert all(v["contacts"] == 100_000 and v["contacts_per_cpu_s"] > 0 for v in res["evaluator"].values())
    assert side["summary"]["note"] == res["note"]
