"""conformal: a finite-element workbench for conformal wheel-rail rolling contact.

Data flows one way: scene -> geometry -> grid -> influence numbers -> solver -> result.
Units everywhere: mm, N, N/mm² (MPa), rad; creepages dimensionless, spin in rad/mm.
"""
from conformal.errors import ConformalError, InputError, NoContactError, ConvergenceError
from conformal.materials import Material

__version__ = "0.1.0"
__all__ = ["ConformalError", "InputError", "NoContactError", "ConvergenceError", "Material",
           "__version__"]
