"""conformal: a finite-element workbench for conformal wheel-rail rolling contact.

Data flows one way: scene -> geometry -> grid -> influence numbers -> solvers -> cases (the
wheel-rail orchestration) -> api / cli.  "seed Eq. N" in the docstrings refers to the review that
seeded the workbench and the primary sources are cited where their equations are implemented
(README, References).  Units everywhere: mm, N, N/mm² (MPa), rad; creepages
dimensionless, spin in rad/mm.

>>> import conformal
>>> r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
...                      "load": {"normal_force": 1e4}, "model": {"theory": "hertz"}})
>>> round(r.FN)
10000
"""
from conformal.errors import ConformalError, InputError, NoContactError, ConvergenceError
from conformal.materials import Material
from conformal.api import load_scene
from conformal.result import Result
# ``conformal.solve`` is the module conformal/solve.py made callable: conformal.solve(scene, **overrides)
# is conformal.api.solve, and ``from conformal.solve import solve_scene`` keeps working
import conformal.solve
from conformal.scene import Scene

__version__ = "0.1.0"
__all__ = ["ConformalError", "InputError", "NoContactError", "ConvergenceError", "Material", "Result",
           "Scene", "load_scene", "solve", "__version__"]
