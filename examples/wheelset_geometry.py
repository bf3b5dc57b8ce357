"""Wheelset geometry: rolling-radius difference and contact angles against the lateral shift.

S1002 wheels on UIC 60 rails inclined 1:40 (the scene ``meshes/scenes/s1002_uic60_sweep.toml``),
the rigid contact geometry of ``conformal sweep`` without solving the contact: the wheelset is
placed at every shift, the roll found so that both wheels touch, and the contact points searched.
The right wheel's contact stays on the tread (contact angle within a few degrees) up to 4.5 mm and
jumps to the gauge corner between 4.5 and 5.0 mm, as in the Manchester benchmark A-2.2 (CONTACT's
results for the same profiles; ``validation/halfspace``).

Run: ``python examples/wheelset_geometry.py [OUT_DIR]`` (writes ``wheelset_geometry.png``).
"""
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from conformal.geometry.sweep import sweep  # noqa: E402
from conformal.scene import load_scene  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)
scene = load_scene(Path(__file__).resolve().parent.parent / "meshes" / "scenes" / "s1002_uic60_sweep.toml")

shifts = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 4.5, 5.0, 5.5, 6.0])
rows = sweep(scene.geometry, shifts, base_dir=scene.base_dir)
dr = np.array([r["delta_r"] for r in rows])
angle = np.degrees([r["contact_angle_right"] for r in rows])

fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6, 5), sharex=True, layout="constrained")
ax1.plot(shifts, dr, "o-")
ax1.set_title("S1002 on UIC 60 (1:40): rigid contact geometry")
ax1.set_ylabel("r_right - r_left [mm]")
ax2.plot(shifts, angle, "o-")
ax2.set_ylabel("contact angle, right [deg]")
ax2.set_xlabel("lateral shift [mm]")
fig.savefig(out / "wheelset_geometry.png", dpi=80)

print(json.dumps({"shift": shifts.tolist(), "delta_r": dr.tolist(), "contact_angle_right_deg": angle.tolist(),
                  "y_rail_right": [r["y_rail_right"] for r in rows]}))
