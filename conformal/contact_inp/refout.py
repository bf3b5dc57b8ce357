"""Totals of CONTACT's reference output (``.ref_out``), per case, for comparisons.

Module 3 blocks (user guide, "Overall output quantities per contact patch"): after "TOTAL FORCES"
the values FN FX FY MZ and the energies, then FN/G, two force or creepage/shift columns, APPROACH,
PMAX; after "CONTACT STATISTICS" NPOT NCON NADH NSLIP.  Values are kept as printed (strings) so
that a comparison can use the printed number of digits.

>>> text = '''
...  Case     1
...  TOTAL FORCES, TORSIONAL MOMENT, ELASTIC ENERGY, FRICTIONAL POWER
...      FN          FX          FY          MZ         ELAST.EN.   FRIC.POWER
...      1.000E+05       9144.   2.592E+04   3.860E+04       3.993  -1.055E+04
...      FN/G      FX/FSTAT/FN  FY/FSTAT/FN  APPROACH     PMAX
...          1.220      0.3048      0.8639   9.089E-02       912.8
...     NPOT   NCON   NADH  NSLIP  INORM  ITANG
...     1989   1027      0   1027      1      1
... '''
>>> r = read_ref_out(text)[1]
>>> r["FX"], r["PMAX"], r["NCON"]
('9144.', '912.8', '1027')
"""
from __future__ import annotations

import re


def read_ref_out(text: str) -> dict[int, dict[str, str]]:
    """{case number: {label: printed value}} of the module-3 totals of a reference output."""
    out: dict[int, dict[str, str]] = {}
    blocks = re.split(r"^ Case +(\d+)\s*$", text, flags=re.M)
    for k in range(1, len(blocks) - 1, 2):
        num, body = int(blocks[k]), blocks[k + 1]
        lines = body.splitlines()
        vals: dict[str, str] = {}
        for i, ln in enumerate(lines):
            labels = re.split(r"\s{2,}", ln.strip())
            if labels[:2] == ["FN", "FX"] or labels[:1] == ["FN/G"] or labels[:1] == ["NPOT"]:
                if i + 1 < len(lines):
                    values = lines[i + 1].split()
                    if len(values) >= len(labels):
                        vals.update(dict(zip(labels, values)))
        if vals:
            out[num] = vals
    return out


#: reference label -> JSON key of ``conformal inp``
KEYS = {"FN": "FN", "FX": "FX", "FY": "FY", "MZ": "MZ", "APPROACH": "approach", "PMAX": "pmax",
        "CREEP X": "xi", "SHIFT X": "xi", "CREEP Y": "eta", "SHIFT Y": "eta",
        "NCON": "n_contact", "NADH": "n_adhesion", "NSLIP": "n_slip"}


def last_digit_unit(printed: str) -> float:
    """The value of one unit in the last printed digit: '9144.' -> 1, '2.592E+04' -> 10, '0.3048' -> 1e-4.

    >>> last_digit_unit("9144."), last_digit_unit("2.592E+04"), last_digit_unit("0.3048")
    (1.0, 10.0, 0.0001)
    """
    s = printed.upper()
    mant, _, expo = s.partition("E")
    frac = mant.split(".")[1] if "." in mant else ""
    return float(f"1e{int(expo or 0) - len(frac)}")


def compare(ours: dict, ref: dict[str, str], *, units: float = 1.0, zero_force: float = 1e-4) -> dict[str, tuple]:
    """{key: (ours, printed reference)} for the quantities that differ by more than ``units`` units
    of the last printed digit (element counts: exactly).  Tangential forces below ``zero_force``
    FN are zero up to round-off in both programs (e.g. CONTACT prints -2.552E-09 N for a force
    that vanishes by symmetry): those compare with that absolute tolerance."""
    bad = {}
    floor = zero_force * abs(float(ref.get("FN", "0")))
    for label, key in KEYS.items():
        if label not in ref or key not in ours or ours[key] is None:
            continue
        printed = ref[label]
        if label in ("NCON", "NADH", "NSLIP"):
            if int(printed) != int(ours[key]):
                bad[key] = (ours[key], printed)
            continue
        tol = units * last_digit_unit(printed) * (1 + 1e-9)
        if key in ("FX", "FY"):
            tol = max(tol, floor)
        elif key in ("xi", "eta"):        # a creepage or shift that vanishes: round-off (1e-12)
            tol = max(tol, 1e-10)
        if abs(float(ours[key]) - float(printed)) > tol:
            bad[key] = (ours[key], printed)
    return bad


def read_ref_out_wheelrail(text: str) -> dict[int, dict]:
    """{case: {"track": {FX(TR): ...}, "patches": [{FN, FX, FS, MN, PMAX, NCON, DELTCP(TR), YCP(R), ...}]}}
    of the module-1 blocks of a reference output (values as printed)."""
    out: dict[int, dict] = {}
    blocks = re.split(r"^ Case +(\d+)\s*$", text, flags=re.M)
    for k in range(1, len(blocks) - 1, 2):
        num, body = int(blocks[k]), blocks[k + 1]
        if "TOTAL FORCES ON RAIL" not in body:
            continue
        parts = re.split(r"^ -+ DATA FOR CONTACT PATCH +\d+ -+\s*$", body, flags=re.M)
        entry = {"track": _labelled(parts[0]), "patches": [_labelled(p) for p in parts[1:]]}
        out[num] = entry
    return out


def _labelled(text: str) -> dict[str, str]:
    vals: dict[str, str] = {}
    lines = text.splitlines()
    for i, ln in enumerate(lines[:-1]):
        labels = re.split(r"\s{2,}", ln.strip())
        values = lines[i + 1].split()
        if len(labels) != len(values):
            labels = ln.split()
        if len(labels) >= 3 and len(values) == len(labels) and all(re.match(r"^[A-Z]", x) for x in labels) \
                and all(re.match(r"^[-+.\d]", v) for v in values):
            vals.update({lab: v for lab, v in zip(labels, values) if lab not in vals})
    return vals


def compare_wheelrail(ours: dict, ref: dict, mu: float) -> dict[str, float]:
    """Deviations of a module-1 result from CONTACT's, each in units of its tolerance (> 1: outside):
    patch forces FN, FX, FS and the track forces within max(1 % |F|, 0.002 mu FN) (the Manchester
    metric of tests/validation/test_manchester.py), contact angle 0.005 rad, lateral position on the rail
    0.2 mm, pmax 3 %, elements in contact 10 %.  Patches are matched in order of y on the rail;
    a different number of patches is reported as ``n_patches``."""
    out: dict[str, float] = {}
    rp = sorted(ref["patches"], key=lambda p: float(p.get("YCP(R)", 0.0)))
    op = sorted(ours["patches"], key=lambda p: p["y_rail"] if p["y_rail"] is not None else 0.0)
    if len(rp) != len(op):
        return {"n_patches": float("inf")}
    fn_total = sum(float(p["FN"]) for p in rp)
    for k, (o, r) in enumerate(zip(op, rp)):
        fn = float(r["FN"])
        floor = 0.002 * mu * fn
        for key, rkey in (("FN", "FN"), ("FX", "FX"), ("FS", "FS")):
            out[f"patch{k + 1}.{key}"] = abs(o[key] - float(r[rkey])) / max(0.01 * abs(float(r[rkey])), floor)
        out[f"patch{k + 1}.contact_angle"] = abs(o["contact_angle"] - float(r["DELTCP(TR)"])) / 0.005
        out[f"patch{k + 1}.y_rail"] = abs(o["y_rail"] - float(r["YCP(R)"])) / 0.2
        if "PMAX" in r:
            out[f"patch{k + 1}.pmax"] = abs(o["pmax"] / float(r["PMAX"]) - 1.0) / 0.03
        if "NCON" in r:
            out[f"patch{k + 1}.n_contact"] = abs(o["n_contact"] / float(r["NCON"]) - 1.0) / 0.10
    floor = 0.002 * mu * fn_total
    for key, rkey in (("FX_track", "FX(TR)"), ("FY_track", "FY(TR)"), ("FZ_track", "FZ(TR)")):
        if rkey in ref["track"]:
            out[key] = abs(ours[key] - float(ref["track"][rkey])) / max(0.01 * abs(float(ref["track"][rkey])), floor)
    return out


def compare_conformal(ours: dict, ref: dict, nomrad: float) -> dict[str, float]:
    """Deviations (%) of a conformal (D = 4) module-1 case from CONTACT's printed values: per patch
    (paired by normal force) the developed normal force against TILDE_FN, the forces in CONTACT's
    "bar" frame (the track-frame patch forces turned by CONTACT's reference angle DELTCP) against
    BAR_FN and BAR_FS, FX against BAR_FX, pmax, the elements in contact; ``angle`` the contact angle's
    difference in degrees; the track forces relative to max(|F|, 1 % of FZ); with a solved pitch
    velocity, the free-rolling pitch creepage omega NOMRAD / V - 1 (VPITCH_WS, VX_WS)."""
    import math

    def pct(a: float, b: float, floor: float = 0.0) -> float:
        return 100.0 * (a - b) / max(abs(b), floor)

    out: dict[str, float] = {}
    rp = sorted(ref["patches"], key=lambda p: -float(p["TILDE_FN"]))
    op = sorted(ours["patches"], key=lambda p: -p["FN"])
    if len(rp) != len(op):
        return {"n_patches": float("inf")}
    for k, (o, r) in enumerate(zip(op, rp), start=1):
        d = float(r["DELTCP(TR)"])                  # rad
        fy, fz = o["FY_track"], o["FZ_track"]
        bar_fn, bar_fs = fz * math.cos(d) - fy * math.sin(d), fy * math.cos(d) + fz * math.sin(d)
        floor = 0.01 * float(r["BAR_FN"])
        out[f"patch{k}.FN"] = pct(o["FN"], float(r["TILDE_FN"]))
        out[f"patch{k}.bar_FN"] = pct(bar_fn, float(r["BAR_FN"]))
        out[f"patch{k}.FX"] = pct(o["FX"], float(r["BAR_FX"]), floor)
        out[f"patch{k}.bar_FS"] = pct(bar_fs, float(r["BAR_FS"]), floor)
        out[f"patch{k}.pmax"] = pct(o["pmax"], float(r["PMAX"]))
        out[f"patch{k}.n_contact"] = pct(o["n_contact"], float(r["NCON"]))
        out[f"patch{k}.angle"] = math.degrees(o["contact_angle"] - d)
    t = ref["track"]
    fz_ref = float(t["FZ(TR)"])
    for key, rkey in (("FX_track", "FX(TR)"), ("FY_track", "FY(TR)"), ("FZ_track", "FZ(TR)")):
        out[key] = pct(ours[key], float(t[rkey]), 0.01 * abs(fz_ref))
    if "pitch_velocity" in ours and "VPITCH_WS" in t:
        v = float(t["VX_WS"])
        out["pitch_creepage"] = pct(-ours["pitch_velocity"] * nomrad / v - 1.0, -float(t["VPITCH_WS"]) * nomrad / v - 1.0)
    return out
