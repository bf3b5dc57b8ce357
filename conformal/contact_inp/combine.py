"""CONTACT's combination of contact regions (module 1, D_SEP, D_COMB, D_TURN, A_SEP) checked
against the patches this reader solves.

CONTACT's user guide (section "Identification of contact patches") measures the distance d between
two interpenetration regions between their extents: the gap between the rolling-direction ranges
[x_sta, x_end], the gap between the lateral ranges [y_sta, y_end] and the difference of the heights
z at the facing lateral ends, d = sqrt(dx^2 + dy^2 + dz^2) (zero where ranges overlap).  With
d_turn >= d_sep >= d_comb and the difference of the regions' weighted contact angles within A_SEP:

* d <= D_COMB: one patch, solved in full;
* D_COMB < d <= D_SEP: one patch with a "blending approach" that attenuates the cross-influence;
* D_SEP < d <= D_TURN (default 2 D_SEP - D_COMB): two patches whose reference angles are turned
  towards their weighted average;
* otherwise (d > D_TURN or angles more than A_SEP apart): two independent patches.

This reader does none of the blending and turning: it forms a patch of the regions closer than a
single distance along the rail profile (``[geometry] patch_combine``; D_SEP on the planar path)
and solves each patch on its own tangent plane or strip.  :func:`combination_warnings` compares
the two at the solved wheelset height and returns one sentence for each pair of neighbouring
regions that CONTACT treats differently, so that such a case is never reported as if it were
CONTACT's.  (CONTACT's near-miss extension, G_MISS >= 0, is not modelled; its default -1 turns
it off.)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: the prefix of every warning of this module (the CLI repeats these lines on stderr)
PREFIX = "patch combination:"


@dataclass(frozen=True)
class Region:
    """One interpenetration region: its extents (side frame, mm), weighted contact angle (rad)
    and the rail arc lengths it covers."""

    x: tuple[float, float]
    y: tuple[float, float]
    z: tuple[float, float]          # heights at the lateral ends y[0], y[1]
    angle: float
    s: tuple[float, float]


def region_distance(a: Region, b: Region) -> float:
    """CONTACT's distance between two interpenetration regions (mm): the gaps between their
    rolling-direction and lateral extents and the height difference at the facing lateral ends."""
    dx = max(a.x[0] - b.x[1], b.x[0] - a.x[1], 0.0)
    if a.y[0] > b.y[1]:
        dy, dz = a.y[0] - b.y[1], a.z[0] - b.z[1]
    elif b.y[0] > a.y[1]:
        dy, dz = b.y[0] - a.y[1], b.z[0] - a.z[1]
    else:
        dy = dz = 0.0
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def contact_treatment(d: float, dangle: float, d_comb: float, d_sep: float, d_turn: float,
                      a_sep: float) -> str:
    """CONTACT's treatment of two regions at distance ``d`` (mm) and contact-angle difference
    ``dangle`` (rad): "combined", "blended", "turned" or "separate" (module docstring)."""
    if abs(dangle) > a_sep or d > d_turn:
        return "separate"
    if d <= d_comb:
        return "combined"
    if d <= d_sep:
        return "blended"
    return "turned"


def regions_at(scene, z: float) -> list[Region]:
    """The interpenetration regions of the scene's wheel at side-frame wheelset height ``z``,
    ordered along the rail profile (every region on its own: no combination).  The wheel is placed
    without searching where it touches (conformal.cases.wheelrail.placed_pair): ``z`` is known."""
    from conformal.cases.wheelrail import placed_pair
    from conformal.geometry.patches import find_patches
    from conformal.geometry.search import pair_locus

    pair, top = placed_pair(scene)[:2]
    rail = pair.rail
    lobes = find_patches(pair.wheel(z), rail, top, d_comb=0.0, locus=pair_locus(pair, top, z))
    out = []
    for p in sorted(lobes, key=lambda p: p.s_range[0]):
        s = np.linspace(p.s_range[0], p.s_range[1], 41)
        pts = rail.point(s)
        i, j = int(np.argmin(pts[:, 0])), int(np.argmax(pts[:, 0]))
        out.append(Region(x=p.x_range, y=(float(pts[i, 0]), float(pts[j, 0])),
                          z=(float(pts[i, 1]), float(pts[j, 1])), angle=p.delta, s=p.s_range))
    return out


def combination_warnings(regions: list[Region], reader_gap: float, d_comb: float, d_sep: float,
                         d_turn: float, a_sep: float) -> list[str]:
    """One warning for each pair of neighbouring regions that CONTACT treats differently from this
    reader, which joins regions less than ``reader_gap`` apart along the rail profile into one
    patch solved in full and solves all others as independent patches."""
    out = []
    for a, b in zip(regions, regions[1:]):
        d = region_distance(a, b)
        how = contact_treatment(d, a.angle - b.angle, d_comb, d_sep, d_turn, a_sep)
        joined = (b.s[0] - a.s[1]) < reader_gap
        ours = "combines them into one patch" if joined else "solves them as separate patches"
        if how == "combined" and not joined:
            out.append(f"{PREFIX} CONTACT combines contact regions closer than D_COMB = {d_comb:g} mm (regions "
                       f"{d:.2f} mm apart); this reader {ours}")
        elif how == "blended":
            out.append(f"{PREFIX} CONTACT blends contact regions between D_COMB = {d_comb:g} and D_SEP = "
                       f"{d_sep:g} mm apart into one patch (regions {d:.2f} mm apart); this reader {ours}")
        elif how == "turned":
            out.append(f"{PREFIX} CONTACT turns the reference angles of contact regions between D_SEP = {d_sep:g} "
                       f"and D_TURN = {d_turn:g} mm apart (regions {d:.2f} mm apart); this reader {ours} "
                       "without turning")
        elif how == "separate" and joined:
            out.append(f"{PREFIX} CONTACT solves contact regions {d:.2f} mm apart as separate patches (D_TURN = "
                       f"{d_turn:g} mm, A_SEP = {a_sep:g} rad); this reader {ours}")
    return out


def reader_gap(scene) -> float:
    """The distance along the rail profile (mm) below which this reader joins contact regions into
    one patch: ``[geometry] patch_combine`` on the planar path; none (0) with conformal strips
    ``[grid] strips = "separate"``, which puts every contact region on a strip of its own."""
    if getattr(scene.grid, "strips", "coupled") == "separate":
        return 0.0
    return float(scene.geometry.patch_combine)


def loaded_warnings(scene, d_comb: float, d_sep: float, d_turn: float, a_sep: float) -> list[str]:
    """The warnings of :func:`combination_warnings` at the height of the scene's normal balance
    alone (conformal.cases.wheelrail.loaded_state, no tangential solve): a survey of a deck's
    cases without solving them; a full solve ends at a slightly different height."""
    from conformal.cases.wheelrail import loaded_state

    _, st, _ = loaded_state(scene, grids=scene.load.wheel_load is not None, warn=False)
    return combination_warnings(regions_at(scene, st.z), reader_gap(scene), d_comb, d_sep, d_turn, a_sep)


def contact_patch_count(regions: list[Region], d_comb: float, d_sep: float, d_turn: float, a_sep: float) -> int:
    """How many patches CONTACT forms from the regions: neighbours that it combines or blends
    (d <= D_SEP, angles within A_SEP) share one patch."""
    if not regions:
        return 0
    return 1 + sum(contact_treatment(region_distance(a, b), a.angle - b.angle, d_comb, d_sep, d_turn, a_sep)
                   not in ("combined", "blended") for a, b in zip(regions, regions[1:]))


def strip_count_warning(regions: list[Region], n_solved: int, d_comb: float, d_sep: float, d_turn: float,
                        a_sep: float) -> list[str]:
    """The warning of a conformal case (separate strips) that solves more or fewer strips than the
    patches CONTACT forms from the interpenetration regions (a region whose contact splits into
    parts gets a strip per part here)."""
    n = contact_patch_count(regions, d_comb, d_sep, d_turn, a_sep)
    if n == n_solved:
        return []
    return [f"{PREFIX} CONTACT forms {n} patch(es) from the {len(regions)} interpenetration region(s) (D_COMB = "
            f"{d_comb:g} mm, D_SEP = {d_sep:g} mm); this reader solves {n_solved} separate strips"]
