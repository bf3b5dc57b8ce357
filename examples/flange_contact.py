"""Conformal contact: the S1002 flange root against the UIC 60 gauge corner.

Solves ``meshes/scenes/flange_s1002_uic60.toml`` (10 kN per wheel, lateral shift 6.2 mm, theory
``conformal`` on the curved rail surface with half-space influence numbers) and the same scene on
the tangent plane (theory ``exact``), then draws the 3-D view (pyvista, off-screen) and the
developed pressure map (matplotlib).  The vertical balance is the check: the wheel load comes
back as the vertical force on the rail, FZ_track, to the balance tolerance (1e-4 of the load).

Run: ``python examples/flange_contact.py [OUT_DIR]`` (writes ``flange_3d.png``, ``flange_map.png``).
"""
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import conformal  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)
scene_file = Path(__file__).resolve().parent.parent / "meshes" / "scenes" / "flange_s1002_uic60.toml"

curved = conformal.solve(scene_file, grid__n=24)
plane = conformal.solve(scene_file, grid__n=24, model__theory="exact")

plotter = curved.plot3d()                  # a new off-screen pyvista plotter (no display needed)
plotter.add_text(f"S1002 flange root on UIC 60: FN {curved.FN / 1000:.1f} kN", font_size=10, color="black")
plotter.screenshot(str(out / "flange_3d.png"), window_size=(800, 600))
plotter.close()

fig, ax = plt.subplots(figsize=(5.5, 3.2), layout="constrained")
curved.plot(ax=ax, quantity="pn")
ax.set_ylabel("s - s_ref [mm] (developed)")
fig.savefig(out / "flange_map.png", dpi=80)

angles = (curved.extra["contact_angle_min"], curved.extra["contact_angle_max"])   # rad
print(json.dumps({"FN": curved.FN, "FZ_track": curved.extra["FZ_track"], "FY_track": curved.extra["FY_track"],
                  "FY_track_tangent_plane": plane.extra["FY_track"], "pmax": curved.pmax,
                  "contact_angle_range_deg": [math.degrees(v) for v in angles],
                  "warnings": curved.warnings}))
