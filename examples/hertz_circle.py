"""Hertzian circle: the exact half-space solver against Hertz's closed form.

A steel ball of radius R = 500 mm on a flat (h = A x² + B y², A = B = 1/(2R)) pressed with
FN = 100 kN and rolling with xi = 0.001 (CONTACT's performance case "circ").  The exact theory's
peak pressure is compared with Hertz's p0 = (6 FN E*² / (pi³ R²))^(1/3), written out here from
Johnson (1985), Eq. 4.23, independent of the package; the FASTSIM answer is printed beside it.

Run: ``python examples/hertz_circle.py [OUT_DIR]`` (writes ``hertz_circle.png``).
"""
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")                      # off-screen: no display needed
import matplotlib.pyplot as plt  # noqa: E402

import conformal  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out")
out.mkdir(parents=True, exist_ok=True)

G, nu, FN, A = 82000.0, 0.28, 100000.0, 0.001
scene = {"material": {"G": G, "nu": nu}, "friction": {"mu": 0.3},
         "geometry": {"kind": "quadratic", "A": A, "B": A},
         "load": {"normal_force": FN}, "kinematics": {"xi": 0.001},
         "grid": {"n": 40}, "model": {"theory": "exact"}}
exact = conformal.solve(scene)
fastsim = conformal.solve(scene, model__theory="fastsim")

# Hertz (Johnson 1985, Eqs. 4.21-4.23): E* of two equal bodies, R from h = x²/(2R)
E = 2.0 * G * (1.0 + nu)
E_star = E / (2.0 * (1.0 - nu**2))
R = 1.0 / (2.0 * A)
p0 = (6.0 * FN * E_star**2 / (math.pi**3 * R**2)) ** (1.0 / 3.0)
a = (3.0 * FN * R / (4.0 * E_star)) ** (1.0 / 3.0)

fig, axes = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
exact.plot(ax=axes[0], quantity="pn")
exact.plot(ax=axes[1], quantity="pt")
fig.savefig(out / "hertz_circle.png", dpi=80)

print(json.dumps({"pmax_exact": exact.pmax, "p0_hertz": p0, "a_hertz": a, "a_exact": exact.a,
                  "FX_exact": exact.FX, "FX_fastsim": fastsim.FX, "converged": exact.converged}))
