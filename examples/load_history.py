"""A load history with memory: Cattaneo's sphere pulled sideways in steps.

A steel sphere (Hertz radius a = 1 mm) is pressed with 1 kN and then pulled tangentially, with the
normal force kept, to FX = -0.25, -0.5 and -0.75 mu FN in three ``[[history]]`` steps (``rolling =
"shift"``, prescribed forces).  Each step starts from the tractions of the one before (seed
Eqs. 39-40).  Cattaneo's solution (Johnson 1985, Section 7.1) gives, per step, the radius of the
stick zone c/a = (1 - |Q|/(mu P))^(1/3) and the tangential shift of two equal bodies
2 x 3 mu P (2 - nu) / (16 G a) (1 - (1 - |Q|/(mu P))^(2/3)); both are printed beside the solver's.

Run: ``python examples/load_history.py [OUT_DIR]`` (writes ``load_history.png``).
"""
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import conformal  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)

G, nu, mu, P, a = 82000.0, 0.28, 0.3, 1000.0, 1.0
steps = (-0.25, -0.5, -0.75)
scene = {"material": {"G": G, "nu": nu}, "friction": {"mu": mu},
         "geometry": {"kind": "hertz", "a": a, "b": a}, "load": {"normal_force": P},
         "grid": {"n": 30}, "model": {"theory": "exact"},
         "history": [{"fx_rel": q} for q in steps]}
r = conformal.solve(scene)
grid = r.extra["grid"]
element = grid["dx"] * grid["dy"]

rows = []
for step, q in zip(r.extra["history"], steps):
    n_stick = step["n_contact"] - step["n_slip"]
    c_over_a = (1.0 - abs(q)) ** (1.0 / 3.0)
    shift = 2 * 3 * mu * P * (2 - nu) / (16 * G * a) * (1 - (1 - abs(q)) ** (2.0 / 3.0))
    rows.append({"FX_rel": q, "c_over_a": math.sqrt(n_stick * element / math.pi) / a,
                 "c_over_a_cattaneo": c_over_a, "shift": abs(step["shift_x"]), "shift_cattaneo": shift})

# the last step's traction along the x axis against Cattaneo's
f = r.field
x = grid["xl"] + (np.arange(grid["mx"]) + 0.5) * grid["dx"]
j = grid["my"] // 2
p0 = 3 * P / (2 * math.pi * a * a)
c = (1.0 - abs(steps[-1])) ** (1.0 / 3.0) * a
xs = np.linspace(-a, a, 401)
q_cat = mu * p0 * (np.sqrt(np.clip(1 - xs**2 / a**2, 0, None)) - c / a * np.sqrt(np.clip(1 - xs**2 / c**2, 0, None)))
fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
ax.plot(xs, q_cat, "k-", label="Cattaneo")
ax.plot(x, -f.px[:, j], "o", ms=4, label="exact solver, y ≈ 0")
ax.set_xlabel("x [mm]")
ax.set_ylabel("-p_x [N/mm²]")
ax.set_title(f"FX = {steps[-1]} μ FN: traction along y = 0")
ax.legend()
fig.savefig(out / "load_history.png", dpi=80)

print(json.dumps({"steps": rows}))
