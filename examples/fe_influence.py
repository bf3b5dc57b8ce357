"""FE influence numbers: a crowned wheel on a flat rail against Hertz.

The scene ``meshes/scenes/hertz_crowned_wheel.toml`` puts a wheel of rolling radius 460 mm and
transverse radius 300 mm on a flat rail at a prescribed approach of 0.05 mm.  The conformal model is
solved twice: with half-space influence numbers and with the finite-element numbers of the two
bodies (gmsh quasi-quarter spaces, scikit-fem, computed once and cached in ``$CONFORMAL_CACHE``).
Both must give Hertz's normal force for the curvatures A = 1/(2 x 460), B = 1/(2 x 300) 1/mm
(Hertz's closed form, ``conformal.theories.hertz``).  The first run meshes and factorises both
bodies (a few seconds); later runs read the cache.

Run: ``python examples/fe_influence.py [OUT_DIR]`` (writes ``fe_influence.png``).
"""
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import conformal  # noqa: E402
from conformal.materials import Material  # noqa: E402
from conformal.theories.hertz import hertz_from_curvatures  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)
scene_file = Path(__file__).resolve().parent.parent / "meshes" / "scenes" / "hertz_crowned_wheel.toml"

fe = conformal.solve(scene_file, grid__n=20)
halfspace = conformal.solve(scene_file, grid__n=20, model__influence="halfspace")
hertz = hertz_from_curvatures(1 / (2 * 460.0), 1 / (2 * 300.0), Material(82000.0, 0.28, 82000.0, 0.28),
                              approach=0.05)

fig, axes = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
fe.plot(ax=axes[0], quantity="pn")
axes[0].set_title("FE influence numbers")
halfspace.plot(ax=axes[1], quantity="pn")
axes[1].set_title("half-space influence numbers")
fig.savefig(out / "fe_influence.png", dpi=80)

print(json.dumps({"FN_fe": fe.FN, "FN_halfspace": halfspace.FN, "FN_hertz": hertz.FN,
                  "pmax_fe": fe.pmax, "pmax_hertz": hertz.pmax, "warnings": fe.warnings}))
