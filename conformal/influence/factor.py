"""Sparse SPD factorisations shared by the FE influence numbers (:mod:`conformal.influence.fe`)
and the direct FE contact solve (:mod:`conformal.fe_contact.solver`): one factorisation of a
stiffness matrix K_ff, then block solves K_ff X = B.

Solvers: ``"pardiso"`` (pypardiso, Intel MKL PARDISO, real symmetric positive definite, mtype 2;
optional dependency), ``"splu"`` (scipy's SuperLU; an ordering per caller, see :class:`Factor`)
and ``"amg"`` (pyamg smoothed aggregation as a preconditioner of conjugate gradients, one
right-hand side at a time, to a relative residual ``amg_tol``; optional dependency).

>>> import scipy.sparse as sp
>>> A = sp.csr_matrix(np.array([[4.0, 1.0], [1.0, 3.0]]))
>>> Factor(A, "splu").solve(np.array([[1.0], [2.0]])).round(6).ravel().tolist()
[0.090909, 0.636364]
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from conformal.errors import ConformalError

#: splu orderings: "COLAMD" (scipy's default; the FE influence numbers) or, for an SPD matrix,
#: "MMD_AT_PLUS_A" with no pivoting in SuperLU's symmetric mode (measured on a 30k-dof P2 body:
#: half the fill and time of COLAMD; the direct FE contact solve)
SPLU_ORDERINGS = ("COLAMD", "MMD_AT_PLUS_A")


class FESolveError(ConformalError):
    """The FE solve failed: out of memory, too many unknowns, or the solver did not converge."""


def pardiso_available() -> bool:
    """Whether pypardiso can be imported."""
    try:
        import pypardiso  # noqa: F401
    except Exception:
        return False
    return True


def amg_available() -> bool:
    """Whether pyamg can be imported."""
    try:
        import pyamg  # noqa: F401
    except Exception:
        return False
    return True


class Factor:
    """A factorised SPD matrix A solving blocks of right-hand sides.

    Parameters
    ----------
    A : the matrix (sparse, symmetric positive definite).
    solver : "pardiso" | "splu" | "amg".
    amg_tol, near_null : AMG: relative residual of CG and the near null space (rigid-body modes).
    ordering : splu only, one of :data:`SPLU_ORDERINGS`; "MMD_AT_PLUS_A" factorises in SuperLU's
        symmetric mode without pivoting (valid because A is SPD).
    release : pardiso only: free PARDISO's memory after each solve (one solve per factorisation,
        as for the influence numbers; pypardiso factorises again on a later solve).
    """

    def __init__(self, A: sp.spmatrix, solver: str, amg_tol: float = 1e-10, near_null=None, *,
                 ordering: str = "COLAMD", release: bool = False):
        self.kind = solver
        self.A = A
        self.iterations = 0
        self._release = release
        if solver == "pardiso":
            import pypardiso

            self._ps = pypardiso.PyPardisoSolver(mtype=2)
            self._ps.set_statistical_info_off()
            self._U = sp.triu(A, format="csr")
            self._U.sort_indices()
            self._ps.factorize(self._U)
        elif solver == "splu":
            from scipy.sparse.linalg import splu

            if ordering not in SPLU_ORDERINGS:
                raise ValueError(f"splu ordering: one of {SPLU_ORDERINGS}, got {ordering!r}")
            if ordering == "COLAMD":
                self._lu = splu(A.tocsc(), permc_spec=ordering)
            else:
                self._lu = splu(A.tocsc(), permc_spec=ordering, diag_pivot_thresh=0.0,
                                options=dict(SymmetricMode=True))
        elif solver == "amg":
            import pyamg

            self._ml = pyamg.smoothed_aggregation_solver(A, B=near_null, symmetry="symmetric",
                                                         strength="symmetric")
            self._tol = amg_tol
        else:
            raise ValueError(f"solver: \"pardiso\", \"splu\" or \"amg\", got {solver!r}")

    def solve(self, B: np.ndarray) -> np.ndarray:
        """X with A X = B (B: (n,) or (n, k))."""
        if self.kind == "pardiso":
            X = self._ps.solve(self._U, np.asfortranarray(B))
            if self._release:
                self._ps.free_memory(everything=True)
            return X.reshape(B.shape)
        if self.kind == "splu":
            return self._lu.solve(B)
        X = np.empty_like(B)
        for k in range(B.shape[1]):
            res: list = []
            X[:, k] = self._ml.solve(B[:, k], tol=self._tol, accel="cg", maxiter=500, residuals=res)
            self.iterations = max(self.iterations, len(res))
            if res and res[-1] > self._tol * max(res[0], 1e-300) * 10:
                raise FESolveError(f"AMG-CG did not converge for right-hand side {k}: relative residual "
                                   f"{res[-1] / res[0]:.2e} after {len(res)} iterations")
        return X
