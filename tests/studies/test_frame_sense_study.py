"""studies/frame_sense.py --quick: the sense of the turned element frames against the FE bodies."""
import json
import runpy
import sys

import pytest
from _paths import STUDIES

STUDY = STUDIES / "frame_sense.py"


@pytest.mark.slow
def test_frame_sense_quick(tmp_path, monkeypatch):
    """The deep pair on an 8 x 8 grid (about 30 s) at the FE FN as load: pmax with the turned frames
    of the project (= Blanco's variant 4) within 0.3 % of the FE bodies' (measured +0.03 %), the
    opposite sense (the project before frames21) further off (measured -0.50 %); the FE kernel with
    its own coupling terms replaced by the turned ones moves FN the way the FE coupling does (up)."""
    monkeypatch.setattr(sys, "argv", [str(STUDY), "--quick", "--out", str(tmp_path)])
    with pytest.raises(SystemExit) as exit_info:
        runpy.run_path(str(STUDY), run_name="__main__")
    assert exit_info.value.code == 0
    (row,) = json.loads((tmp_path / "frame_sense.json").read_text())
    fe = row["at_load"]["fe"]["pmax"]
    now, before = row["at_load"]["turned- (now)"]["pmax"], row["at_load"]["turned+ (before)"]["pmax"]
    assert abs(now / fe - 1) < 0.003 and abs(before / fe - 1) > 2 * abs(now / fe - 1)
    c = row["coupling_FN"]
    assert (c["fe"] - c["fe uncoupled"]) * (c["fe + coupling of turned-"] - c["fe uncoupled"]) > 0
    assert (c["fe"] - c["fe uncoupled"]) * (c["fe + coupling of turned+"] - c["fe uncoupled"]) < 0
    assert (tmp_path / "run.json").is_file()
