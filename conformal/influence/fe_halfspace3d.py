"""The interior half-space field of a uniformly loaded rectangle, for the FE split method.

The closed forms live in :mod:`conformal.stresses.rectangle` (the subsurface stresses of issue 24
superpose them, and the stresses layer sits below :mod:`conformal.result` so that
``Result.stresses`` can reach them); this module re-exports them under their old names.
"""
from conformal.stresses.rectangle import (  # noqa: F401
    _displacement_local,
    _gauss_rectangle_displacement,
    _gauss_rectangle_stress,
    _point_displacement_local,
    _point_stress_local,
    _stress_from,
    point_displacement,
    rectangle_displacement,
    rectangle_stress,
)
