"""Results: totals, per-element fields and convergence, the same type for every model.

Sign convention (CONTACT, module 3): tractions and forces act on body 1 (the body the normal n
points into); creepages are those of body 1 relative to body 2, so a positive xi gives FX < 0.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field as dc_field, is_dataclass
from typing import Any, Mapping

import numpy as np

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
        X, Y = self.grid.mesh()
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

    FN, FX, FY (N), MZ (N mm) on body 1; a, b (mm) the semi-axes of the contact (Hertz
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

    def summary(self) -> dict[str, Any]:
        """The JSON summary printed by ``conformal solve`` (public field names: add, never rename)."""
        out: dict[str, Any] = {
            "theory": self.theory, "FN": self.FN, "FX": self.FX, "FY": self.FY, "MZ": self.MZ,
            "a": self.a, "b": self.b, "pmax": self.pmax, "approach": self.approach,
            "xi": self.xi, "eta": self.eta, "phi": self.phi,
            "n_contact": self.n_contact, "n_slip": self.n_slip,
            "converged": self.converged, "iterations": self.iterations, "residual": self.residual,
            "wall_s": self.wall_s,
        }
        if self.patches:
            out["patches"] = [p.summary() for p in self.patches]
        out.update(self.extra)
        return _jsonable(out)
