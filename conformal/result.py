"""Results: totals, per-element fields and convergence, the same type for every model.

Sign convention (CONTACT, module 3): tractions and forces act on body 1 (the body the normal n
points into); creepages are those of body 1 relative to body 2, so a positive xi gives FX < 0.
The fields of the JSON summary and the keys of ``Result.extra``, with their units, are listed in
:mod:`conformal.schema`.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field as dc_field, is_dataclass
from typing import Any, Mapping

import numpy as np

from conformal.errors import InputError
from conformal.grid import PlanarGrid

# element status flags in TractionField.status
EXTERIOR, ADHESION, SLIP = 0, 1, 2


@dataclass(frozen=True, eq=False)
class TractionField:
    """Per-element solution on a grid; every array has the grid's shape (mx, my).

    pn, px, py : tractions on body 1 (N/mm²); status: EXTERIOR / ADHESION / SLIP;
    sx, sy : slip (relative slip velocity / V for rolling, slip distance for shift), may be None;
    un, ux, uy : displacement differences (mm), may be None.
    """

    grid: PlanarGrid
    pn: np.ndarray
    px: np.ndarray
    py: np.ndarray
    status: np.ndarray
    sx: np.ndarray | None = None
    sy: np.ndarray | None = None
    un: np.ndarray | None = None
    ux: np.ndarray | None = None
    uy: np.ndarray | None = None

    @property
    def n_contact(self) -> int:
        return int(np.count_nonzero(self.status != EXTERIOR))

    @property
    def n_slip(self) -> int:
        return int(np.count_nonzero(self.status == SLIP))

    @property
    def n_adhesion(self) -> int:
        return int(np.count_nonzero(self.status == ADHESION))

    def totals(self) -> tuple[float, float, float, float]:
        """FN, FX, FY, MZ with MZ = sum(x py - y px) dA about the grid origin."""
        dA = self.grid.area
        g = self.grid
        if isinstance(g, PlanarGrid):   # the centres broadcast: the products and sums of mesh() without the copies
            X, Y = g.x[:, None], g.y[None, :]
        else:
            X, Y = g.mesh()
        return (float(self.pn.sum() * dA), float(self.px.sum() * dA), float(self.py.sum() * dA),
                float((X * self.py - Y * self.px).sum() * dA))


def _jsonable(v: Any) -> Any:
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, (np.floating, np.integer)):
        return _jsonable(v.item())
    if isinstance(v, np.ndarray):
        return [_jsonable(x) for x in v.tolist()] if v.ndim else _jsonable(v.item())
    if isinstance(v, Mapping):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if is_dataclass(v) and not isinstance(v, type):
        return _jsonable(asdict(v))
    return v


@dataclass(frozen=True, eq=False)
class Result:
    """The answer of one model to one contact problem (or the sum over patches).

    FN, FX, FY (N), MZ (N mm) on body 1, in the contact frame: FY is the lateral force in the contact
    plane (also written ``FS`` in the JSON; a wheel-rail result's track-frame lateral force on the
    rail is ``extra["FY_track"]``); a, b (mm) the semi-axes of the contact (Hertz
    ellipse or the extent of the computed patch); pmax (N/mm²); approach (mm); xi, eta, phi the
    creepages used (solved ones where forces were prescribed).
    """

    theory: str
    FN: float
    FX: float
    FY: float
    MZ: float
    a: float
    b: float
    pmax: float
    approach: float
    xi: float = 0.0
    eta: float = 0.0
    phi: float = 0.0
    converged: bool = True
    wall_s: float = 0.0
    iterations: int | None = None
    residual: float | None = None
    field: TractionField | None = None
    patches: tuple["Result", ...] = ()
    extra: Mapping[str, Any] = dc_field(default_factory=dict)

    @classmethod
    def combined(cls, results: "list[Result] | tuple[Result, ...]", theory: str,
                 extra: Mapping[str, Any] | None = None) -> "Result":
        """The totals over several patches (or strips) as one Result: FN, FX, FY, MZ and wall_s
        add, pmax is the largest, converged all; a, b, approach and the creepages are those of the
        most loaded patch; ``patches`` lists the parts.  Forces are summed as given, i.e. all parts
        must report forces in one common frame.

        >>> p = Result("exact", FN=2.0, FX=-1.0, FY=0.5, MZ=0.0, a=3.0, b=2.0, pmax=9.0, approach=0.1)
        >>> q = Result("exact", FN=1.0, FX=-0.5, FY=0.0, MZ=1.0, a=1.0, b=1.0, pmax=12.0, approach=0.2)
        >>> r = Result.combined([p, q], "exact")
        >>> r.FN, r.FX, r.MZ, r.pmax, r.a, r.approach, len(r.patches)
        (3.0, -1.5, 1.0, 12.0, 3.0, 0.1, 2)
        """
        main = max(results, key=lambda r: r.FN)
        return cls(theory=theory, FN=sum(r.FN for r in results), FX=sum(r.FX for r in results),
                   FY=sum(r.FY for r in results), MZ=sum(r.MZ for r in results), a=main.a, b=main.b,
                   pmax=max(r.pmax for r in results), approach=main.approach, xi=main.xi, eta=main.eta,
                   phi=main.phi, converged=all(r.converged for r in results),
                   wall_s=sum(r.wall_s for r in results), patches=tuple(results), extra=dict(extra or {}))

    @property
    def n_contact(self) -> int | None:
        if self.field is not None:
            return self.field.n_contact
        if self.patches and all(p.n_contact is not None for p in self.patches):
            return sum(p.n_contact for p in self.patches)
        return None

    @property
    def n_slip(self) -> int | None:
        if self.field is not None:
            return self.field.n_slip
        if self.patches and all(p.n_slip is not None for p in self.patches):
            return sum(p.n_slip for p in self.patches)
        return None

    @property
    def warnings(self) -> list[str]:
        """Warnings about this result and its patches (physically questionable input or output),
        each once, in order: ``extra["warnings"]`` of the total, then of every patch."""
        out: list[str] = []
        for w in list(self.extra.get("warnings", ())) + [w for p in self.patches for w in p.warnings]:
            if w not in out:
                out.append(str(w))
        return out

    def to_dict(self) -> dict[str, Any]:
        """The result as plain JSON-ready Python values (the JSON summary of ``conformal solve``:
        totals, convergence, ``patches``, the model's extra fields and ``warnings``).

        >>> import conformal
        >>> r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
        ...                      "load": {"normal_force": 1e4}, "model": {"theory": "hertz"}})
        >>> d = r.to_dict()
        >>> d["theory"], round(d["FN"]), d["warnings"]
        ('hertz', 10000, [])
        """
        return self.summary()

    def plot(self, ax=None, quantity: str = "pn", patch: int | None = None):
        """Draw the result into a matplotlib Axes and return the Axes.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (a new pyplot figure when omitted).
        quantity : {"pn", "pt", "status"}
            Pressure, tangential traction with its direction, or the adhesion/slip areas.
        patch : int, optional
            Which patch of a multi-patch result (default: the most loaded one).

        Returns
        -------
        matplotlib.axes.Axes

        Examples
        --------
        >>> import conformal
        >>> from matplotlib.figure import Figure
        >>> r = conformal.solve({"geometry": {"kind": "quadratic", "A": 1e-3, "B": 1e-3},
        ...                      "load": {"normal_force": 1e4}, "kinematics": {"xi": 1e-3},
        ...                      "grid": {"n": 12}, "model": {"theory": "exact"}})
        >>> ax = r.plot(Figure().subplots(), quantity="pt")
        >>> ax.get_title().startswith("traction, FX")
        True
        """
        from conformal.plots import plot_pressure

        return plot_pressure(self, ax, quantity=quantity, patch=patch)

    def plot3d(self, plotter=None, scalar: str = "pn"):
        """Add the result to a pyvista Plotter (a new off-screen one if None) and return it: for a
        conformal result the rail, the wheel and the tractions in 3-D; see :func:`conformal.plots.plot3d`.

        Examples
        --------
        >>> import conformal, pyvista
        >>> r = conformal.solve("meshes/scenes/flange_s1002_uic60.toml")      # doctest: +SKIP
        >>> r.plot3d(pyvista.Plotter()).show()                                 # doctest: +SKIP
        """
        from conformal.plots import plot3d

        return plot3d(self, plotter, scalar=scalar)

    def _stress_source(self, patch: int | None):
        """The traction field for the stresses: this result's, or a patch's (default: the most loaded)."""
        if patch is None and self.field is not None:
            return self
        if not self.patches:
            if patch not in (None, 0):
                raise InputError(f"patch: this result has no patches, got patch={patch!r}")
            return self
        if patch is None:
            patch = int(np.argmax([p.FN for p in self.patches]))
        if not (isinstance(patch, int) and 0 <= patch < len(self.patches)):
            raise InputError(f"patch: must be an index in [0, {len(self.patches) - 1}], got {patch!r}")
        return self.patches[patch]

    def stresses(self, points, *, nu: float = 0.28, body: int = 1, patch: int | None = None) -> np.ndarray:
        """Half-space stress tensors (N/mm², tension positive) at ``points`` (..., 3) in mm, from
        the solved tractions (superposed closed-form fields of the loaded elements; see
        :func:`conformal.stresses.halfspace.stresses` for the frames).  ``nu``: Poisson's ratio of
        the body (default steel's 0.28); ``body`` 1 (the rail) or 2; ``patch`` of a multi-patch
        result (default: the most loaded).  Returns (..., 3, 3).

        Examples
        --------
        >>> import conformal
        >>> r = conformal.solve({"geometry": {"kind": "hertz", "a": 2.0, "b": 2.0},
        ...                      "load": {"normal_force": 1e4}, "grid": {"n": 21},
        ...                      "model": {"theory": "exact"}})
        >>> s = r.stresses([0.0, 0.0, 0.96], nu=0.3)      # 0.48 a below the centre
        >>> bool(abs(0.5 * (s[0, 0] - s[2, 2]) / r.pmax - 0.31) < 0.01)
        True
        """
        from conformal.stresses.halfspace import stresses

        src = self._stress_source(patch)
        if src.field is None:
            raise InputError(f"stresses: the {self.theory!r} result has no traction field (use a theory with a grid)")
        return stresses(src.field, points, nu=nu, body=body)

    def stress_field(self, depths=None, *, depth: float | None = None, n_depths: int = 40, nu: float = 0.28,
                     body: int = 1, patch: int | None = None):
        """Half-space stresses on depth planes below the patch (FFT per plane), as a
        :class:`conformal.stresses.field.StressField` (``summary()`` gives the maxima and the Dang
        Van index).  ``depths`` (mm), else ``n_depths`` from 0 to ``depth`` (default twice the
        smaller semi-axis).  Planar results: planes below the element centres; conformal strips:
        lines along the normals of the element centres (rail-profile frame)."""
        from conformal.stresses.field import default_depths, stress_field

        src = self._stress_source(patch)
        if src.field is None:
            raise InputError(f"stresses: the {self.theory!r} result has no traction field (use a theory with a grid)")
        if depths is None:
            depths = default_depths(src.a, src.b, depth, n_depths)
        return stress_field(src.field, depths, nu=nu, body=body)

    def summary(self) -> dict[str, Any]:
        """The JSON summary printed by ``conformal solve`` (public field names: add, never rename)."""
        out: dict[str, Any] = {
            "theory": self.theory, "FN": self.FN, "FX": self.FX, "FY": self.FY, "FS": self.FY, "MZ": self.MZ,
            "a": self.a, "b": self.b, "pmax": self.pmax, "approach": self.approach,
            "xi": self.xi, "eta": self.eta, "phi": self.phi,
            "n_contact": self.n_contact, "n_slip": self.n_slip,
            "converged": self.converged, "iterations": self.iterations, "residual": self.residual,
            "wall_s": self.wall_s,
        }
        if self.patches:
            out["patches"] = [p.summary() for p in self.patches]
        out.update(self.extra)
        out["warnings"] = self.warnings
        return _jsonable(out)
