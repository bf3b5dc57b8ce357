"""studies/contact_side_by_side.py: the checks it makes before timing (a CONTACT whose answers differ
from its reference output, or from ours by more than 1 %, stops the study) and its one-line errors.
Timing needs a CONTACT executable, which CI does not have; the check logic runs on CONTACT's own
reference output standing in for a fresh ``.out`` (the same format)."""
from __future__ import annotations

import subprocess
import sys

import pytest
from _paths import ROOT
from _studies import load_study

from conformal.contact_inp.refout import read_ref_out


def _study():
    return load_study("contact_side_by_side")


def test_check_accepts_contacts_reference_and_ours_within_one_percent():
    mod = _study()
    job = mod.JOBS["mbench_right"]
    text = job["ref"].read_text()
    fn = {k: float(v["FN"]) for k, v in read_ref_out(text).items()}
    assert len(fn) == 21
    ours = {k: v * (1.0 + 0.004 * (-1) ** k) for k, v in fn.items()}
    got = mod.check_contact(job, text, ours)
    assert got["cases"] == 21 and got["fn_vs_reference_digits"] == 0.0
    assert got["max_fn_error_ours"] == pytest.approx(0.004, rel=1e-9)


def test_check_stops_on_a_contact_that_differs_from_its_reference():
    mod = _study()
    job = mod.JOBS["mbench_right"]
    text = job["ref"].read_text()
    assert " 9997. " in text                        # case 1's FN as printed
    bad = text.replace(" 9997. ", " 9999. ", 1)     # two units of the last printed digit
    with pytest.raises(SystemExit, match="FN of case 1 is 9999."):
        mod.check_contact(job, bad, {1: 9997.0})


def test_check_stops_when_ours_is_more_than_one_percent_off():
    mod = _study()
    job = mod.JOBS["mbench_right"]
    text = job["ref"].read_text()
    with pytest.raises(SystemExit, match="1.50 % from CONTACT's"):
        mod.check_contact(job, text, {1: 9997.0 * 1.015})


@pytest.mark.parametrize("args, line", [([], "give CONTACT's executable"),
                                        (["--contact", "/no/such/contact"], "not an executable file"),
                                        (["--contact", sys.executable, "--jobs", "x"], "--jobs: choose from")])
def test_bad_arguments_give_one_line_and_exit_2(args, line):
    p = subprocess.run([sys.executable, str(ROOT / "studies" / "contact_side_by_side.py"), *args],
                       capture_output=True, text=True, env={"PATH": "/usr/bin:/bin"}, timeout=60)
    assert p.returncode == 2
    assert p.stderr.strip().count("\n") == 0 and line in p.stderr
