"""Wheelset dynamics: the seed's suspended wheelset (Table 1) on tangent track (seed Eqs. 50-61).

* :mod:`conformal.dynamics.scene`: the vehicle scene (TOML, SI units), unknown keys rejected;
* :mod:`conformal.dynamics.contact`: contact-geometry table from the profile contact search,
  Hertz normal force with damping (Eq. 57);
* :mod:`conformal.dynamics.creep`: creep-force models (registry);
* :mod:`conformal.dynamics.model`: equations of motion; :mod:`conformal.dynamics.simulate`:
  integration, history and summary; :mod:`conformal.dynamics.stability`: critical speeds;
* :mod:`conformal.dynamics.plots`, :mod:`conformal.dynamics.cli` (``conformal simulate``,
  ``conformal stability``).

Nothing below this package imports it.
"""
