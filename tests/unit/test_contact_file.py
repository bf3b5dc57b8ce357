"""CONTACT's file of numerical influence coefficients (C3 = 9; user guide, appendix "Specification
of the file of numerical influence coefficients"): the layout, a round trip of the project's
half-space numbers, an independent value (Love's centre displacement of a square load) and the
scene key ``[model] influence_file``."""
from __future__ import annotations

import io
import math

import numpy as np
import pytest

import conformal
from conformal.errors import InputError
from conformal.influence.contact_file import read_contact_file, write_contact_file
from conformal.influence.curved import curved_halfspace_kernel
from conformal.materials import Material

MAT = Material(G1=82000.0, nu1=0.28, G2=60000.0, nu2=0.30)      # dissimilar: coupling K != 0


def planar_kernel(mx=5, my=4, dx=0.5, dy=0.4, mat=MAT):
    """The project's planar half-space numbers of an mx x my grid as a strip kernel."""
    return curved_halfspace_kernel(mx, dx, (np.arange(my) + 0.5) * dy, np.full(my, dy), np.zeros(my), mat)


def _written(K, **kw) -> str:
    buf = io.StringIO()
    write_contact_file(buf, K, **kw)
    return buf.getvalue()


def test_round_trip_of_the_halfspace_numbers():
    """Written in CONTACT's layout and read back: the same numbers to round-off (C = G K is written
    with 17 digits; dividing by G again costs at most an ulp)."""
    K = planar_kernel()
    f = read_contact_file(io.StringIO(_written(K, dx=0.5, dy=0.4, G=MAT.G)))
    assert (f.nmatrix, f.iaconvex, f.mx, f.my, f.dx, f.dy) == (1, 1, 5, 4, 0.5, 0.4)   # one matrix: Toeplitz in y
    back = f.kernel(MAT.G)
    assert back.shape == K.shape
    assert np.abs(back - K).max() <= 2e-16 * np.abs(K).max()
    # one matrix per loaded row (numbers that depend on the row, not only on iy - jy)
    K2 = K * (1.0 + 0.1 * np.arange(4))[None, None, :, None, None]
    f2 = read_contact_file(io.StringIO(_written(K2, dx=0.5, dy=0.4, G=MAT.G, iaconvex=2)))
    assert (f2.nmatrix, f2.iaconvex) == (4, 2)
    assert np.abs(f2.kernel(MAT.G) - K2).max() <= 2e-16 * np.abs(K2).max()


def test_layout_is_the_user_guides():
    """4 header lines, 2 comment lines, then per offset iyofs = -my+1 .. my-1 two comment lines and
    mx lines 'ixofs xrel Czz Czx Czy Cxz Cxx Cxy Cyz Cyx Cyy'; the loaded element's own Czz is
    Love's centre displacement of a uniformly loaded square, C = 4 (1 - nu) asinh(1) d / pi
    (two identical bodies, G-scaled), independent of the project's reader."""
    mat = Material.identical(82000.0, 0.28)
    mx, my, d = 3, 2, 0.4
    text = _written(planar_kernel(mx, my, d, d, mat), dx=d, dy=d, G=mat.G)
    lines = text.splitlines()
    data = [ln for ln in lines if not ln.lstrip().startswith("%")]
    assert len(data) == 4 + (2 * my - 1) * mx
    assert [int(v) for v in data[0].split()[:2]] == [1, 1]          # nmatrix, iaconvex
    assert [int(v) for v in data[1].split()[:2]] == [0, 312]        # lquasid, xyzorder
    assert [int(v) for v in data[2].split()[:2]] == [1, 0]          # lsymmx, lsymmy
    assert data[3].split()[:4] == ["3", "2", "0.4", "0.4"]
    assert lines[4].startswith("%") and lines[5].startswith("%")     # the two comment lines
    body = lines[6:]
    for k in range(2 * my - 1):                                       # per offset: 2 comments + mx rows
        block = body[k * (mx + 2):(k + 1) * (mx + 2)]
        assert block[0].startswith("%") and block[1].startswith("%")
        assert [int(r.split()[0]) for r in block[2:]] == list(range(mx))
    row = [float(v) for v in data[4 + (my - 1) * mx].split()]         # iyofs = 0, ixofs = 0
    assert row[0] == 0 and row[1] == 0.0
    assert row[2] == pytest.approx(4 * (1 - 0.28) * math.asinh(1.0) * d / math.pi, rel=1e-12)   # Czz
    assert row[3] == 0.0 and row[5] == 0.0                           # Czx, Cxz: K = 0
    assert row[6] > 0 and row[10] > 0                                # Cxx, Cyy


def test_reads_contacts_own_writer_layout():
    """CONTACT's own writer (src/m_inflcf.f90, inflcf_print) puts three comment lines per offset;
    the numbers alone fix the layout, so that file reads the same."""
    K = planar_kernel()
    text = _written(K, dx=0.5, dy=0.4, G=MAT.G)
    more = "\n".join(ln + ("\n% one more comment" if ln.startswith("% offset") else "") for ln in text.splitlines())
    f = read_contact_file(io.StringIO(more))
    assert np.abs(f.kernel(MAT.G) - K).max() <= 2e-16 * np.abs(K).max()


def test_bad_files_are_refused():
    K = planar_kernel(3, 2)
    text = _written(K, dx=0.5, dy=0.4, G=MAT.G)
    lines = text.splitlines()
    cases = [("   0  123      % lquasid", 1, "lquasid"), ("   0    0", 2, "lsymmx"), ("   3    1", 0, "nmatrix")]
    for new, k, match in cases:
        data_idx = [i for i, ln in enumerate(lines) if not ln.startswith("%")][k]
        bad = lines[:data_idx] + [new] + lines[data_idx + 1:]
        with pytest.raises(InputError, match=match):
            read_contact_file(io.StringIO("\n".join(bad)))
    with pytest.raises(InputError, match="expected .* lines of numbers"):
        read_contact_file(io.StringIO("\n".join(lines[:-1])))
    skew = K.copy()
    skew[0] *= 1.5                                    # no longer symmetric in x
    with pytest.raises(InputError, match="symmetry in x"):
        write_contact_file(io.StringIO(), skew, dx=0.5, dy=0.4, G=MAT.G)


def test_scene_key_reads_a_contact_file(tmp_path):
    """``[model] influence_file`` with CONTACT's file of the grid's own half-space numbers solves
    the same problem as the built-in numbers; a file for a smaller grid is refused."""
    d = {"material": {"G": MAT.G1, "nu": MAT.nu1, "body2": {"G": MAT.G2, "nu": MAT.nu2}},
         "geometry": {"kind": "quadratic", "A": 1e-3, "B": 1.5e-3},
         "friction": {"mu": 0.3}, "load": {"approach": 0.004}, "kinematics": {"xi": 1e-3},
         "grid": {"mx": 14, "my": 12, "dx": 0.35, "dy": 0.3}, "model": {"theory": "exact"}}
    ref = conformal.solve(d)
    g = ref.field.grid
    path = tmp_path / "inflcf.txt"
    write_contact_file(path, planar_kernel(g.mx, g.my, g.dx, g.dy), dx=g.dx, dy=g.dy, G=MAT.G)
    d["model"] = dict(d["model"], influence_file=str(path))
    r = conformal.solve(d)
    assert r.FN == pytest.approx(ref.FN, rel=1e-9) and r.FX == pytest.approx(ref.FX, rel=1e-7)
    write_contact_file(path, planar_kernel(g.mx - 2, g.my, g.dx, g.dy), dx=g.dx, dy=g.dy, G=MAT.G)
    with pytest.raises(InputError, match="smaller"):
        conformal.solve(d)
