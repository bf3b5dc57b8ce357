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
        if abs(float(ours[key]) - float(printed)) > tol:
            bad[key] = (ours[key], printed)
    return bad
