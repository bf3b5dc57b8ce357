"""``[model] theory = "table"``: creep forces from a creep-force table (:mod:`conformal.tables`).

``[model] table = "path.npz"`` names the table (a relative path is relative to the scene file's
folder, resolved when the scene is read, :func:`conformal.scene.scene_from_dict` with ``base_dir``;
``"default"`` or no key: the table shipped with the package).  The contact must be
Hertzian (quadratic geometry), steady rolling with prescribed creepages, and one friction
coefficient; the Hertz solution gives a, b, pmax and the approach, the table gives FX, FY, MZ
(:func:`conformal.tables.table.evaluate`, Eqs. T1-T2).  A point outside the table's ranges is an
InputError naming the range (never an extrapolation).

>>> from conformal.scene import scene_from_dict
>>> from conformal.problem import problems_from_scene
>>> s = scene_from_dict({"material": {"G": 82000, "nu": 0.28}, "friction": {"mu": 0.3},
...     "geometry": {"kind": "hertz", "a": 6.0, "b": 6.0}, "load": {"normal_force": 1e5},
...     "kinematics": {"xi": 0.03}, "model": {"theory": "table"}})
>>> r = solve(problems_from_scene(s)[0])
>>> r.theory, round(r.FX / (0.3 * r.FN), 3)
('table', -1.0)
"""
from __future__ import annotations

import math

from conformal.errors import InputError
from conformal.result import Result
from conformal.tables.table import evaluate, load_table


def solve(problem) -> Result:
    """Solve one contact problem with a creep-force table."""
    from conformal.theories.linear import material_notes, steady_hertz

    hz = steady_hertz(problem, "table")
    kin, mat, fr = problem.kinematics, problem.material, problem.friction
    if kin.fx_rel is not None or kin.fy_rel is not None:
        raise InputError("[kinematics] fx_rel: theory \"table\" takes creepages, not prescribed forces "
                         "(use theory = \"exact\" or \"linear\")")
    if fr.mu_static != fr.mu_kinetic:
        raise InputError(f"[friction] mu_static: theory \"table\" has one friction coefficient, got mu_static = "
                         f"{fr.mu_static} and mu_kinetic = {fr.mu_kinetic}")
    opts = problem.model.options
    path = opts.get("table")
    if path is not None and not isinstance(path, str):
        raise InputError(f"[model] table: must be a file name, got {path!r}")
    try:
        table = load_table(path)
    except InputError as exc:        # the file's problem, named by the key that gave it
        msg = str(exc)
        raise InputError(msg if msg.startswith("[model] table") else f"[model] table: {msg}") from None
    FX, FY, MZ = evaluate(table, hz.a, hz.b, hz.FN, fr.mu, mat.G, mat.nu, kin.xi, kin.eta, kin.phi)
    extra = {"table": table.path, "table_hash": table.content_hash[:16], **material_notes(problem)}
    FX, FY, MZ = float(FX), float(FY), float(MZ)
    extra["F_over_muFN"] = math.hypot(FX, FY) / (fr.mu * hz.FN)
    return Result(theory="table", FN=hz.FN, FX=FX, FY=FY, MZ=MZ, a=hz.a, b=hz.b, pmax=hz.pmax,
                  approach=hz.approach, xi=kin.xi, eta=kin.eta, phi=kin.phi, extra=extra)
