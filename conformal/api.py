"""The Python API: solve a scene from a notebook or a script in one call.

>>> import conformal
>>> r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
...                      "load": {"normal_force": 1e4}, "kinematics": {"xi": 1e-3},
...                      "model": {"theory": "fastsim"}}, model__theory="exact", grid__n=20)
>>> r.theory, round(r.FN), r.FX < 0
('exact', 10000, True)
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from conformal.result import Result
from conformal.scene import Scene, as_scene

__all__ = ["load_scene", "solve", "sweep"]


def load_scene(source: Scene | str | Path | Mapping[str, Any], **overrides: Any) -> Scene:
    """A validated :class:`~conformal.scene.Scene` from a TOML file, a mapping or a scene.

    Parameters
    ----------
    source : Scene, str, pathlib.Path or mapping
        A scene file (TOML, see docs/reference/scene-files.md), the same content as a dict, or a
        scene to change.
    **overrides
        Keys to change, written ``section__key=value`` (``model__theory="exact"``,
        ``geometry__lateral_shift=5.0``, ``grid__n=30``); see :meth:`Scene.with_`.

    Returns
    -------
    Scene

    Raises
    ------
    InputError
        A missing file, bad TOML, an unknown or bad key (the message names it).

    Examples
    --------
    >>> s = load_scene({"geometry": {"kind": "hertz", "a": 6.0, "b": 6.0},
    ...                 "load": {"normal_force": 1e5}}, model__theory="hertz")
    >>> s.geometry.kind, s.model.theory
    ('hertz', 'hertz')
    """
    return as_scene(source, **overrides)


def solve(scene: Scene | str | Path | Mapping[str, Any], **overrides: Any) -> Result:
    """Solve a scene with the model it names and return the :class:`~conformal.result.Result`.

    Parameters
    ----------
    scene : Scene, str, pathlib.Path or mapping
        What :func:`load_scene` takes.
    **overrides
        ``section__key=value`` changes applied first, e.g. ``model__theory="exact"``.

    Returns
    -------
    Result
        Totals ``FN, FX, FY, MZ`` (N, N mm; FY is the lateral force in the contact plane, the
        track-frame lateral force of a wheel-rail scene is ``extra["FY_track"]``), ``pmax``,
        ``approach``, the traction field, ``warnings``; ``to_dict()`` gives the JSON summary and
        ``plot()`` / ``plot3d()`` draw it.

    Examples
    --------
    >>> r = solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
    ...            "load": {"normal_force": 1e4}, "model": {"theory": "hertz"}})
    >>> round(r.pmax, 1), round(r.a, 3)     # Hertz: a = (3 F R / 4 E*)^(1/3), R = 500 mm
    (464.8, 3.205)
    """
    from conformal.dispatch import solve_scene

    return solve_scene(as_scene(scene, **overrides))


def sweep(scene: Scene | str | Path | Mapping[str, Any], shift: Any = "0:10:0.5", *, workers: int | None = None,
          **overrides: Any):
    """Solve a wheel-rail scene at every lateral shift and return the table of results.

    Parameters
    ----------
    scene : Scene, str, pathlib.Path or mapping
        A wheel-rail scene (what :func:`load_scene` takes).
    shift : str, float or sequence of float
        Lateral shifts (mm): ``"start:stop:step"`` (stop included), one value or a list.
    workers : int, optional
        Processes for FE influence numbers missing from the cache (theory "conformal" with
        influence "fe"; default: cores / 2).
    **overrides
        ``section__key=value`` changes applied first.

    Returns
    -------
    conformal.cases.sweep.SweepTable
        ``table["FN"]``, ``table["FY_track"]``, ... (one value per shift), ``table.units``,
        ``to_csv(path)`` (units in the header), ``to_json(path)``, ``plot(path)``.

    Examples
    --------
    >>> import conformal
    >>> from conformal.cli import demo_scene_path
    >>> t = conformal.sweep(demo_scene_path(), shift=[0.0, 2.0], model__theory="hertz")
    >>> [round(v) for v in t["FZ_track"]], t.units["FN"]
    ([10000, 10000], 'N')
    """
    from conformal.cases.sweep import parse_shifts, solve_sweep

    return solve_sweep(as_scene(scene, **overrides), parse_shifts(shift), workers=workers)
