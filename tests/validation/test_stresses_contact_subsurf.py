"""Subsurface stresses against CONTACT's public example ``examples/subsurf`` (issue 24, item 5).

CONTACT (E.A.H. Vollebregt, github.com/eve70a/CONTACT, Apache-2.0, revision 2707) computes the
half-space stresses below a unit square [-0.4999, 0.5001] x [-0.4998, 0.5002] (one element) with
G = 1, nu = 0.28: case 1 pn = 1; case 2 pn = 1 and px = 0.999 (its full table of points is
``subsurf.ref_subs``).  The reference files in ``tests/reference/contact_subsurf/`` (input deck,
printed output, and a subset of the point table) are CONTACT's, see the README there; the
stresses here come from conformal.stresses (Love / Cerruti closed forms), written independently.
"""
from pathlib import Path

import numpy as np
import pytest

from conformal.grid import PlanarGrid
from conformal.result import TractionField
from conformal.stresses.halfspace import stresses
from conformal.stresses.invariants import max_principal, von_mises
from _paths import REFERENCE

REF = REFERENCE / "contact_subsurf"
CENTRE = np.array([1e-4, 2e-4, 0.0])          # XL + DX/2, YL + DY/2 of the deck
NU = 0.28
# the deck's second block of points (x = y, 21 values; z, 15 values)
XY = np.array([-5.0, -3.0, -2.0, -1.0, -0.8, -0.6, -0.4, -0.3, -0.2, -0.1, 0.0,
               0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0, 2.0, 3.0, 5.0])
Z = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.25, 1.667, 2.5, 5.0])


def read_subs(path: Path) -> np.ndarray:
    """Rows (x, y, z, ux, uy, uz, sighyd, sigvm, sxx, sxy, sxz, syy, syz, szz) of a CONTACT .subs
    file (the line after each '%   NX' comment is a block header, not a point)."""
    rows, skip = [], False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("%"):
            skip = line.split()[1:2] == ["NX"]
            continue
        if skip:
            skip = False
            continue
        if line.strip():
            rows.append([float(v) for v in line.split()])
    return np.array(rows)


def square(px: float) -> TractionField:
    g = PlanarGrid.centred(1, 1, 1.0, 1.0)
    one = np.ones((1, 1))
    return TractionField(g, pn=one, px=px * one, py=0 * one, status=one.astype(int))


def test_case2_point_table():
    """Case 2 (pn = 1, px = 0.999): the six stresses, von Mises and the hydrostatic stress at all
    750 points of the subset (z = 0 ... 5, on and off the loaded square) within 2e-5 (CONTACT
    prints six digits; measured: 5e-6)."""
    d = read_subs(REF / "subsurf.ref_subs_subset")
    assert d.shape == (750, 14)
    S = stresses(square(0.999), d[:, :3] - CENTRE, nu=NU)
    for (i, j), col in {(0, 0): 8, (0, 1): 9, (0, 2): 10, (1, 1): 11, (1, 2): 12, (2, 2): 13}.items():
        assert np.abs(S[:, i, j] - d[:, col]).max() < 2e-5, (i, j)
    assert np.abs(von_mises(S) - d[:, 7]).max() < 2e-5
    assert np.abs(np.trace(S, axis1=1, axis2=2) / 3 - d[:, 6]).max() < 2e-5


def printed_maxima(case: int, block: int) -> dict:
    """'MAX SIGVM = 0.665 AT (X,Y,Z) = (0.000, 0.000, 0.400)' lines of subsurf.ref_out."""
    text = (REF / "subsurf.ref_out").read_text(encoding="utf-8")
    part = text.split(" Case ")[case].split(f"SUBSURFACE STRESSES BLOCK  {block}:")[1].split("SUBSURFACE")[0]
    out = {}
    for line in part.splitlines():
        if "AT (X,Y,Z)" in line:
            key = line.split("=")[0].split()[-1]
            val = float(line.split("=")[1].split()[0])
            pos = [float(v) for v in line.split("(")[-1].rstrip(")").split(",")]
            out[key] = (val, pos)
    return out


@pytest.mark.parametrize("case, px", [(1, 0.0), (2, 0.999)])
def test_printed_block_maxima(case, px):
    """The maxima CONTACT prints for block 2 (21 x 21 x 15 points): von Mises, Tresca s1 - s3, the
    largest s1, smallest s3, and the extreme sxx, syy, szz, sighyd, each within 1e-3 (printed to
    three decimals) at the printed point."""
    X, Y, ZZ = np.meshgrid(XY, XY, Z, indexing="ij")
    P = np.stack([X, Y, ZZ], axis=-1).reshape(-1, 3)
    S = stresses(square(px), P - CENTRE, nu=NU)
    ev = np.linalg.eigvalsh(S)
    values = {"SIGVM": von_mises(S), "SIGTR": ev[:, 2] - ev[:, 0], "SIGMA1": max_principal(S),
              "SIGMA3": ev[:, 0], "SIGXX": S[:, 0, 0], "SIGYY": S[:, 1, 1], "SIGZZ": S[:, 2, 2],
              "SIGHYD": np.trace(S, axis1=1, axis2=2) / 3}
    ref = printed_maxima(case, 2)
    assert set(ref) == set(values)
    for key, (val, pos) in ref.items():
        v = values[key]
        i = int(np.argmin(v)) if key == "SIGMA3" or val < 0 else int(np.argmax(v))
        assert v[i] == pytest.approx(val, abs=1e-3), key
        at = P[np.abs(v - v[i]) < 1e-9]                      # ties (symmetric points)
        assert np.min(np.abs(at - pos).max(axis=1)) < 1e-9, key
