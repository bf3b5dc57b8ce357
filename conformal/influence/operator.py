"""The influence-operator protocol and its one factory.

Every solver (:mod:`conformal.solvers`) takes an operator built here and uses it only through
the members of :class:`InfluenceOperator`: the products, the self terms, and what an operator
may offer beyond them (a preconditioner of the normal problem, single-precision tangential
products, the same numbers on a longer grid, the operator of a coarser grid).  An operator that
cannot offer one of these returns None and the solver does without it; solvers never ask which
class an operator is, and never build one from the model's strings.

Operators (all in :mod:`conformal.influence`):

* :class:`~conformal.influence.halfspace.HalfSpaceInfluence`: planar half-space, uniform grid
  (block Toeplitz, FFT products); offers every optional member.
* :class:`~conformal.influence.curved.CurvedInfluence`: x-invariant strip kernels (curved
  half-space numbers, FE numbers, numbers read from files:
  :class:`~conformal.influence.contact_file.FileInfluence`); products only.
* :class:`~conformal.influence.halfplane.LineInfluence`: two half-planes (line contact); products
  and extension.

>>> from conformal.grid import PlanarGrid
>>> from conformal.materials import Material
>>> op, info = build_operator(PlanarGrid.centred(8, 6, 0.5, 0.5), Material.steel())
>>> (op.mx, op.my), info["influence"], op.extended(1).mx, op.coarsened(2, 2).my
((8, 6), 'halfspace', 9, 3)
"""
from __future__ import annotations

import time
from typing import Any, Callable, Mapping, Protocol

import numpy as np

from conformal.errors import InputError
from conformal.grid import CurvedGrid, PlanarGrid
from conformal.materials import Material

#: the names of the planar half-space numbers and of the curved ones ([model] influence)
PLANAR_KINDS = ("halfspace",)
CURVED_KINDS = ("halfspace", "halfspace_planar", "halfspace_blanco", "fe")


class InfluenceOperator(Protocol):
    """What the solvers may ask of an influence operator of an mx x my grid.

    Tractions act on body 1, displacements are the differences body 1 - body 2 at the element
    centres; components (x, y or s, n) in each element's frame.
    """

    mx: int
    my: int

    @property
    def coupled(self) -> bool:
        """Whether normal and tangential components interact (A_nt != 0)."""

    def apply(self, p: np.ndarray) -> np.ndarray:
        """u = A p, p and u of shape (3, mx, my)."""

    def apply_normal(self, pn: np.ndarray) -> np.ndarray:
        """u_n = A_nn p_n."""

    def apply_tangential(self, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u_x, u_y) = A_tt (p_x, p_y)."""

    def apply_coupling_nt(self, px: np.ndarray, py: np.ndarray) -> np.ndarray:
        """u_n = A_nt p_t (zeros where not coupled)."""

    def apply_coupling_tn(self, pn: np.ndarray) -> np.ndarray:
        """(u_x, u_y) = A_tn p_n, shape (2, mx, my) (zeros where not coupled)."""

    def self_influence(self) -> np.ndarray:
        """A_ij of an element on itself: (3, 3), or (my, 3, 3) per column of a strip."""

    def dense(self) -> np.ndarray:
        """The 3N x 3N matrix (tests and small grids)."""

    def contact_modulus(self) -> float | None:
        """E* (N/mm²) where the operator has one pair of elastic constants, else None."""

    def normal_preconditioner(self) -> Callable[[np.ndarray], np.ndarray] | None:
        """An approximate inverse of A_nn (for projected CG), or None."""

    def tangential_product32(self) -> Callable[[np.ndarray], np.ndarray] | None:
        """A_tt p in single precision, (2, mx, my) -> (2, mx, my) float32, or None."""

    def extended(self, ncols: int) -> "InfluenceOperator | None":
        """The same numbers on a grid ``ncols`` elements longer in x (downstream), or None."""

    def coarsened(self, fx: int, fy: int) -> "InfluenceOperator | None":
        """The operator of the grid of fx x fy merged elements, or None."""

    def window(self, mx: int, my: int) -> "InfluenceOperator | None":
        """The operator of a window of mx x my elements of this grid (the same numbers between the
        elements in it: operators invariant to translations in x and y), or None."""


#: the members every operator has (tests/unit/test_architecture.py checks the classes against it)
PROTOCOL_MEMBERS = ("mx", "my", "coupled", "apply", "apply_normal", "apply_tangential", "apply_coupling_nt",
                    "apply_coupling_tn", "self_influence", "dense", "contact_modulus", "normal_preconditioner",
                    "tangential_product32", "extended", "coarsened", "window")


def build_operator(grid: PlanarGrid | CurvedGrid, material: Material, *, influence: str = "halfspace",
                   influence_file=None, line: bool = False, ref_length: float | None = None,
                   options: Mapping[str, Any] | None = None, bodies: bool = True, cache=None,
                   rail_points=None, wheel_points=None) -> tuple[InfluenceOperator, dict]:
    """The influence operator of a potential contact grid: the one factory of the package.

    Parameters
    ----------
    grid : PlanarGrid or CurvedGrid
        The potential contact grid.
    material : Material
        The two bodies' elastic constants.
    influence : str
        ``[model] influence``: "halfspace" (planar grid: the half-space numbers; curved grid: per
        element pair, frames turned by the contact angles), "halfspace_planar" (curved grid: the
        same numbers without the turn between element frames, CONTACT's conformal approach),
        "halfspace_blanco" (curved grid: those numbers with Blanco-Lorenzo's correction, CONTACT's
        C3 = 4; ``options`` blanco_variant, blanco_method) or "fe" (curved grid: finite elements of the
        real wheel and rail, cached).
    influence_file : path, optional
        Planar grid: read the numbers from this file (:mod:`conformal.influence.contact_file`).
    line : bool
        Planar grid with one element across (my = 1): the two half-planes of line contact, with
        reference length ``ref_length`` (mm; default from the grid).
    options : mapping, optional
        ``[model]`` options of the FE numbers (``fe_*``) and of Blanco's correction (``blanco_*``).
    bodies : bool
        Whether the bodies' geometry is known (wheel-rail scenes); FE numbers need it.
    cache, rail_points, wheel_points
        FE numbers: the cache and the whole profiles the FE bodies are cut from.

    Returns
    -------
    (operator, info)
        info: ``influence`` (the kind), ``influence_s`` (seconds to build) and, for FE numbers,
        ``fe`` (their statistics).

    Raises
    ------
    InputError
        An unknown kind, or one the grid cannot take.
    """
    t0 = time.perf_counter()
    if isinstance(grid, CurvedGrid):
        op, info = _curved(grid, material, influence, options, bodies, cache, rail_points, wheel_points)
    else:
        if influence not in PLANAR_KINDS:
            raise InputError(f"[model] influence: a planar grid takes {PLANAR_KINDS}, got {influence!r}")
        if influence_file is not None:
            from conformal.influence.contact_file import influence_operator

            try:
                op = influence_operator(influence_file, mx=grid.mx, ms=grid.my, dx=grid.dx, ds=grid.dy,
                                        K=material.K, G=material.G)
            except InputError as exc:   # the file's problem, named by the key that gave it
                msg = str(exc)
                raise InputError(msg if msg.startswith("[model] influence_file") else
                                 f"[model] influence_file: {msg}") from None
            info = {"influence": "file"}
        elif line:
            from conformal.influence.halfplane import LineInfluence

            op = LineInfluence.for_grid(grid, material, ref_length=ref_length)
            info = {"influence": "halfplane"}
        else:
            from conformal.influence.halfspace import HalfSpaceInfluence

            op = HalfSpaceInfluence.for_grid(grid.mx, grid.my, grid.dx, grid.dy, material)
            info = {"influence": influence}
    info["influence_s"] = time.perf_counter() - t0
    return op, info


def _curved(grid: CurvedGrid, material: Material, influence: str, options, bodies: bool, cache, rail_points,
            wheel_points) -> tuple[InfluenceOperator, dict]:
    from conformal.influence.curved import CurvedInfluence, curved_halfspace_kernel

    if influence not in CURVED_KINDS:
        raise InputError(f"[model] influence: a curved grid takes {CURVED_KINDS}, got {influence!r}")
    if influence == "fe":
        if not bodies:
            raise InputError("[model] influence: finite-element influence numbers need the bodies' geometry: "
                             "a wheel_rail scene (planar scenes: influence = \"halfspace\")")
        from conformal.influence.factor import FESolveError
        from conformal.influence.fe import settings_from_options, wheel_rail_kernel

        settings = settings_from_options(options if options is not None else {})
        try:
            kernel, stats = wheel_rail_kernel(grid, material, settings, cache=cache, rail_points=rail_points,
                                              wheel_points=wheel_points)
        except (RuntimeError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:   # not ConformalError
            raise FESolveError(f"[model] influence: the FE influence numbers failed on this {grid.mx} x {grid.ms} "
                               f"grid ({type(exc).__name__}: {exc}); try influence = \"halfspace\" or other "
                               "[grid] n / fe_* settings") from exc
        return CurvedInfluence.from_kernel(kernel), {"influence": "fe", "fe": stats}
    # "halfspace_planar": CONTACT's conformal approach (its D = 4 with C3 = 2): the planar half-space
    # numbers on the developed (x, s) grid, every element in its own local frame but no turn between
    # the frames of two elements (Vollebregt 2014; CONTACT user guide, digit C3)
    kernel = curved_halfspace_kernel(grid.mx, grid.dx, grid.s - grid.s_ref, grid.ds, grid.delta, material,
                                     angle_correction=influence == "halfspace")
    if influence == "halfspace_blanco":     # CONTACT's C3 = 4: Blanco-Lorenzo's angle correction of those numbers
        from conformal.influence.blanco import blanco_kernel, linear_fit

        options = options if options is not None else {}
        alpha = np.asarray(grid.delta, float)      # CONTACT's inclination per row (its curv_incln)
        if options.get("blanco_method", "full") == "linear":
            alpha = linear_fit(grid.s, alpha)
        kernel = blanco_kernel(kernel, alpha, int(options.get("blanco_variant", 3)))
    return CurvedInfluence.from_kernel(kernel), {"influence": influence}
