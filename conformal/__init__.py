"""conformal: a finite-element workbench for conformal wheel-rail rolling contact.

Data flows one way: scene -> geometry -> grid -> influence numbers -> solvers -> cases (the
wheel-rail orchestration) -> api / cli.  "seed Eq. N" in the docstrings refers to the review that
seeded the workbench and the primary sources are cited where their equations are implemented
(docs/references.md).  Units everywhere: mm, N, N/mm² (MPa), rad; creepages
dimensionless, spin in rad/mm.

>>> import conformal
>>> r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
...                      "load": {"normal_force": 1e4}, "model": {"theory": "hertz"}})
>>> round(r.FN)
10000
"""
from conformal.errors import ConformalError, InputError, NoContactError, ConvergenceError

__version__ = "0.1.0"
__all__ = ["ConformalError", "InputError", "NoContactError", "ConvergenceError", "Material", "Result",
           "Scene", "load_scene", "solve", "sweep", "__version__"]

# numpy, scipy and the solvers load on first use (issue 23: ``import conformal`` stays light)
_LAZY = {"Material": ("conformal.materials", "Material"), "load_scene": ("conformal.api", "load_scene"),
         "Result": ("conformal.result", "Result"), "Scene": ("conformal.scene", "Scene"),
         "sweep": ("conformal.api", "sweep")}


def solve(scene, **overrides):
    """Solve a scene (a :class:`Scene`, a TOML path or a dict, with ``section__key=value``
    overrides) and return its :class:`Result`: :func:`conformal.api.solve`, loaded on first use.
    (The dispatch of a scene to its model is :mod:`conformal.dispatch`.)"""
    import importlib

    return importlib.import_module("conformal.api").solve(scene, **overrides)


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module 'conformal' has no attribute {name!r}")
    import importlib

    module, attr = _LAZY[name]
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
