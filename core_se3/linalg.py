"""Sparse direct solvers for the (non-symmetric) tangent.

``mumps``: PETSc/MUMPS LU through petsc4py (Debian's python3-petsc4py; with OpenBLAS it was
the fastest measured here, see ``benchmarks/``).  ``superlu``: SciPy's SuperLU with the
MMD_AT_PLUS_A ordering (about 2-3x faster than its default COLAMD on shell matrices).
``auto`` picks MUMPS when petsc4py imports and SuperLU otherwise.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from .errors import SingularSystemError

__all__ = ["make_solver", "available_solvers", "checked_solve"]


def checked_solve(solver, K, b, rtol=1e-6):
    """Solve K x = b and verify the linear residual: a (near-)singular tangent that the
    factorisation let through is reported, never returned as an answer."""
    x = solver.solve(K, b)
    res = np.linalg.norm(K @ x - b)
    if not np.isfinite(res) or res > rtol * max(np.linalg.norm(b), 1e-300):
        raise SingularSystemError(f"tangent is singular or nearly so (linear residual {res:.2e} "
                                  f"vs |b| = {np.linalg.norm(b):.2e})")
    return x


def _have_petsc():
    try:
        import petsc4py  # noqa: F401
        from petsc4py import PETSc  # noqa: F401
        return True
    except Exception:
        return False


def available_solvers():
    return ["superlu"] + (["mumps"] if _have_petsc() else [])


class SuperLUSolver:
    name = "superlu"

    def solve(self, K, b):
        try:
            lu = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A")
        except RuntimeError as exc:
            raise SingularSystemError(f"tangent is singular ({exc})") from None
        x = lu.solve(b)
        if not np.all(np.isfinite(x)):
            raise SingularSystemError("tangent is singular (non-finite solution)")
        return x


class MumpsSolver:
    name = "mumps"

    def __init__(self):
        from petsc4py import PETSc
        self.PETSc = PETSc

    def solve(self, K, b):
        PETSc = self.PETSc
        K = K.tocsr()
        A = PETSc.Mat().createAIJ(size=K.shape, csr=(K.indptr.astype(PETSc.IntType),
                                                      K.indices.astype(PETSc.IntType), K.data),
                                  comm=PETSc.COMM_SELF)
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setOperators(A)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
        ksp.setErrorIfNotConverged(True)
        x = A.createVecLeft()
        bb = A.createVecRight()
        bb.setArray(b)
        try:
            ksp.setUp()
            ksp.solve(bb, x)
        except PETSc.Error as exc:
            raise SingularSystemError(f"tangent is singular (MUMPS: {exc})") from None
        finally:
            ksp.destroy()
            A.destroy()
        out = x.getArray().copy()
        x.destroy()
        bb.destroy()
        if not np.all(np.isfinite(out)):
            raise SingularSystemError("tangent is singular (non-finite solution)")
        return out


def make_solver(name="auto"):
    if name == "auto":
        name = "mumps" if _have_petsc() else "superlu"
    if name == "superlu":
        return SuperLUSolver()
    if name == "mumps":
        if not _have_petsc():
            raise ValueError("solver 'mumps' needs petsc4py (Debian: python3-petsc4py); use 'superlu'")
        return MumpsSolver()
    raise ValueError(f"unknown linear solver {name!r}; choose auto, mumps or superlu")
