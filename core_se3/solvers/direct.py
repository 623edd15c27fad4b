"""The sparse direct solvers behind ``solvers.linalg`` (each ``factor(K)`` returns a context
manager that yields ``solve(b)``; K arrives as CSR arrays of the equilibrated tangent):

* ``superlu``: SciPy's SuperLU with the MMD_AT_PLUS_A ordering and diagonal pivoting (COLAMD
  with partial pivoting as the fallback);
* ``banded``: LAPACK's banded LU with partial pivoting (dgbtrf/dgbtrs) in a reverse
  Cuthill-McKee ordering computed once per pattern: for the narrow patterns of strips and
  beams, where SuperLU's set-up costs more than the factorisation itself;
* ``mumps``: PETSc/MUMPS LU through petsc4py (imported at the first use), with its analysis
  kept while the pattern stays; ``mumps_inertia`` counts eigenvalue signs by LDL^T.

Each factor also gives the sign of det K from the factors already in hand (``Factor.sign``: the
diagonal of U and the parities of the row and column permutations; MUMPS computes the
determinant itself, ICNTL(33)): a change of that sign between two states of a path is an odd
number of real eigenvalues through zero, a critical point (``solvers.newton``'s stability check).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import SingularSystemError

__all__ = ["CsrArrays", "Factor", "finite_solution", "have_petsc", "available_solvers", "SuperLUSolver",
           "BandedSolver", "MumpsSolver", "mumps_inertia"]

class CsrArrays:
    """The arrays of a CSR matrix (data, indices, indptr, shape) without a scipy object: what
    the solvers' ``factor`` reads (``tocsr()`` returns itself)."""
    __slots__ = ("data", "indices", "indptr", "shape")

    def __init__(self, data, indices, indptr, shape):
        self.data, self.indices, self.indptr, self.shape = data, indices, indptr, tuple(shape)

    def tocsr(self):
        return self



def have_petsc():
    """petsc4py is installed (found without importing it: the import costs ~0.5 s)."""
    import importlib.util
    return importlib.util.find_spec("petsc4py") is not None


def available_solvers():
    """The linear solvers this installation has.

    Returns
    -------
    list of str
        'superlu' and 'banded' always, 'mumps' when petsc4py imports.

    Example
    -------
    >>> "superlu" in available_solvers(), "banded" in available_solvers()
    (True, True)
    """
    return ["superlu", "banded"] + (["mumps"] if have_petsc() else [])


class Factor:
    """Context manager holding a factorisation; calling it solves for one right-hand side.
    ``sign()``: +1 or -1, the sign of det K from the factors (None when the solver cannot
    tell); it stays valid after the context closes, until the solver factors again.
    ``solve_transpose`` (None when the solver has none) solves with the transpose on the same
    factors (the adjoint sensitivities of a control session, ``core_se3.control``)."""

    def __init__(self, solve, release=lambda: None, sign=lambda: None, solve_transpose=None):
        self._solve, self._release, self.sign = solve, release, sign
        self.solve_transpose = solve_transpose

    def __enter__(self):
        return self._solve

    def __exit__(self, *exc):
        self._release()
        return False


def permutation_parity(p):
    """+1 for an even permutation p of 0..n-1, -1 for an odd one: (-1)^(n - its cycles), the
    cycles counted as the connected components of the graph i -> p[i] (no Python loop).

    Example
    -------
    >>> permutation_parity([0, 1, 2]), permutation_parity([1, 0, 2]), permutation_parity([1, 2, 0])
    (1, -1, 1)
    """
    from scipy.sparse.csgraph import connected_components
    p = np.asarray(p, np.int64)
    n = len(p)
    if n == 0 or np.array_equal(p, np.arange(n)):
        return 1
    graph = sp.csr_matrix((np.ones(n), (np.arange(n), p)), shape=(n, n))
    cycles, _ = connected_components(graph, directed=True, connection="weak")
    return -1 if (n - cycles) % 2 else 1


def _pivot_sign(diag):
    """Sign of the product of the pivots (None when one is zero or not finite)."""
    if not np.all(np.isfinite(diag)) or np.any(diag == 0):
        return None
    return -1 if np.count_nonzero(diag < 0) % 2 else 1


def finite_solution(x):
    if not np.all(np.isfinite(x)):
        raise SingularSystemError("tangent is singular (non-finite solution)")
    return x


class SuperLUSolver:
    name = "superlu"

    def factor(self, K):
        # On the equilibrated tangent (unit diagonal) a diagonal-preferring factorisation with
        # the symmetric-pattern ordering keeps the fill of a shell matrix small; threshold
        # pivoting (SciPy's default) inflates it by 10x or more.  Accuracy is guarded by
        # checked_solve's refinement and backward-error test; COLAMD with partial pivoting is
        # the fallback when a pivot breaks down.
        # The CSR arrays of K are the CSC arrays of K^T: factor K^T (no conversion) and solve
        # with trans="T", i.e. K x = b.
        if isinstance(K, CsrArrays) or sp.isspmatrix_csr(K):
            A, trans = sp.csc_matrix((K.data, K.indices, K.indptr), shape=K.shape[::-1]), "T"
        else:
            A, trans = K.tocsc(), "N"
        try:
            lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options=dict(SymmetricMode=True))
            x = lu.solve(np.ones(A.shape[0]), trans=trans)
            if not np.all(np.isfinite(x)):
                raise RuntimeError("non-finite")
        except RuntimeError:
            try:
                lu = spla.splu(A, permc_spec="COLAMD")
            except RuntimeError as exc:
                raise SingularSystemError(f"tangent is singular ({exc})") from None

        def sign():
            # A = Pr^T L U Pc^T with a unit-diagonal L; det A^T = det A
            s = _pivot_sign(lu.U.diagonal())
            return None if s is None else s * permutation_parity(lu.perm_r) * permutation_parity(lu.perm_c)

        flip = "N" if trans == "T" else "T"
        return Factor(lambda b: finite_solution(lu.solve(b, trans=trans)), sign=sign,
                      solve_transpose=lambda b: finite_solution(lu.solve(b, trans=flip)))

    def solve(self, K, b):
        with self.factor(K) as solve:
            return solve(b)


class _BandLayout:
    """Where the entries of a CSR pattern go in LAPACK's band storage, in a reverse Cuthill-
    McKee ordering (``perm``): entry (i, j) of P K P^T at ab[kl + ku + i - j, j] (dgbtrf's
    layout, kl extra rows for the row interchanges), as flat Fortran-order positions."""

    def __init__(self, indptr, indices, n):
        from scipy.sparse.csgraph import reverse_cuthill_mckee
        self.indptr, self.indices, self.n = indptr, indices, int(n)
        pattern = sp.csr_matrix((np.ones(len(indices)), indices, indptr), shape=(n, n))
        self.perm = np.asarray(reverse_cuthill_mckee(pattern, symmetric_mode=False), np.int64)
        r, c = self._rows_cols()
        self.kl = int(max(np.max(r - c), 0)) if len(c) else 0
        self.ku = int(max(np.max(c - r), 0)) if len(c) else 0
        self.ldab = 2 * self.kl + self.ku + 1
        # dgbtrf's work: about n kl (kl + ku) multiply-adds
        self.cost = float(n) * max(self.kl, 1) * (self.kl + self.ku + 1)
        self._rc = (r, c)
        self._flat = None

    def _rows_cols(self):
        """(row, column) of every stored entry in the permuted numbering."""
        iperm = np.empty(self.n, np.int64)
        iperm[self.perm] = np.arange(self.n)
        return (iperm[np.repeat(np.arange(self.n), np.diff(self.indptr))],
                iperm[np.asarray(self.indices, np.int64)])

    def release(self):
        """Drop the per-entry arrays (a pattern too wide to be factored banded: ``auto`` keeps
        only its verdict); ``flat`` builds them again if asked."""
        self._rc = self._flat = None

    @property
    def flat(self):
        """Flat Fortran-order position in ab of every stored entry (built at the first use)."""
        if self._flat is None:
            r, c = self._rc if self._rc is not None else self._rows_cols()
            self._flat = (self.kl + self.ku + r - c) + self.ldab * c
            self._rc = None
        return self._flat

    def matches(self, K):
        return (K.indptr is self.indptr and K.indices is self.indices) or (
            K.shape[0] == self.n and K.indptr.shape == self.indptr.shape and K.indices.shape == self.indices.shape
            and np.array_equal(K.indptr, self.indptr) and np.array_equal(K.indices, self.indices))


class BandedSolver:
    """LAPACK's banded LU with partial pivoting (dgbtrf/dgbtrs) in a reverse Cuthill-McKee
    ordering computed once per sparsity pattern.  For the narrow meshes of strips, beams and
    rings (a bandwidth of a few nodes) it factors 2-3x faster than SuperLU, whose set-up
    dominates at a few hundred unknowns (``benchmarks/speed.py``); ``auto`` uses it while
    ``BANDED_MAX_COST`` allows.

    Example
    -------
    >>> import numpy as np, scipy.sparse as sp
    >>> K = sp.diags([-1.0, 4.0, -2.0], [-1, 0, 1], shape=(6, 6)).tocsr()
    >>> x = BandedSolver().solve(K, np.ones(6))
    >>> bool(np.allclose(K @ x, 1.0))
    True
    """
    name = "banded"

    def __init__(self):
        self._layout = None

    def layout(self, K):
        """The band layout of K's pattern (kept while the pattern stays)."""
        lay = self._layout
        if lay is None or not lay.matches(K):
            lay = self._layout = _BandLayout(K.indptr, K.indices, K.shape[0])
        return lay

    def factor(self, K):
        from scipy.linalg import lapack
        if not (isinstance(K, CsrArrays) or sp.isspmatrix_csr(K)):
            K = K.tocsr()
        lay = self.layout(K)
        ab = np.zeros(lay.ldab * lay.n)
        ab[lay.flat] = K.data
        lu, ipiv, info = lapack.dgbtrf(ab.reshape((lay.ldab, lay.n), order="F"), lay.kl, lay.ku, overwrite_ab=1)
        if info != 0:
            raise SingularSystemError(f"tangent is singular (banded LU: zero pivot {info})" if info > 0
                                      else f"banded LU: illegal argument {-info}")
        perm, kl, ku = lay.perm, lay.kl, lay.ku

        def solve(b, trans=0):
            y, inf = lapack.dgbtrs(lu, kl, ku, b[perm], ipiv, trans=trans)
            x = np.empty_like(y)
            x[perm] = y
            return finite_solution(x)

        def sign():
            # P K P^T = Pi L U (the ordering is a similarity): U's diagonal is row kl + ku of
            # the band storage, and each ipiv[i] != i is one row interchange (SciPy's wrapper
            # returns LAPACK's pivots 0-based)
            s = _pivot_sign(lu[kl + ku])
            swaps = np.count_nonzero(ipiv != np.arange(lay.n))
            return None if s is None else s * (-1 if swaps % 2 else 1)

        return Factor(solve, sign=sign, solve_transpose=lambda b: solve(b, 1))   # (P K P^T)^T = P K^T P^T

    def solve(self, K, b):
        with self.factor(K) as solve:
            return solve(b)


class MumpsSolver:
    """PETSc/MUMPS LU.  The PETSc matrix and solver are kept from one factorisation to the next
    while the sparsity pattern stays the same, so MUMPS redoes only the numerical
    factorisation (its ordering and symbolic analysis are reused)."""
    name = "mumps"

    def __init__(self):
        from petsc4py import PETSc
        self.PETSc = PETSc
        self._kept = None           # (indptr, indices, A, ksp, x, bb) of the last pattern
        self._busy = False

    def _objects(self, K):
        PETSc = self.PETSc
        kept = self._kept
        if kept is not None and not self._busy and kept[0].shape == K.indptr.shape and \
                kept[1].shape == K.indices.shape and np.array_equal(kept[0], K.indptr) and \
                np.array_equal(kept[1], K.indices):
            A, ksp = kept[2], kept[3]
            np.copyto(kept[6], K.data)          # the matrix shares this buffer (no insertion)
            A.assemble()
            ksp.setOperators(A)
            return kept, True
        if kept is not None and not self._busy:
            self._destroy(kept)
        indptr = K.indptr.astype(PETSc.IntType)
        indices = K.indices.astype(PETSc.IntType)
        data = np.array(K.data, dtype=PETSc.ScalarType)  # owned here, shared with the matrix
        A = PETSc.Mat().createAIJWithArrays(K.shape, (indptr, indices, data), comm=PETSc.COMM_SELF)
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setOperators(A)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
        pc.setFactorSetUpSolverType()
        pc.getFactorMatrix().setMumpsIcntl(33, 1)      # the determinant (its sign: Factor.sign)
        ksp.setErrorIfNotConverged(True)
        objs = (indptr, indices, A, ksp, A.createVecLeft(), A.createVecRight(), data)
        return objs, False

    @staticmethod
    def _destroy(objs):
        for obj in objs[2:6]:
            obj.destroy()

    def close(self):
        """Free the kept PETSc matrix, solver and MUMPS factors (also when the solver is
        collected: petsc4py does not free them with their Python objects, about 100 MB per
        64x64 shell factorisation)."""
        if self._kept is not None:
            self._destroy(self._kept)
            self._kept = None

    def __del__(self):
        try:
            self.close()
        except Exception:           # at interpreter exit PETSc may be finalised already
            pass

    def factor(self, K):
        PETSc = self.PETSc
        K = K.tocsr()
        objs, reused = self._objects(K)
        _, _, A, ksp, x, bb, _ = objs
        keep = not self._busy
        try:
            ksp.setUp()
        except PETSc.Error as exc:
            self._destroy(objs)
            if reused:
                self._kept = None
            raise SingularSystemError(f"tangent is singular (MUMPS: {exc})") from None
        if keep:
            self._kept, self._busy = objs, True

        def solved_by(ksp_solve, b):
            """x from ``ksp.solve`` or ``ksp.solveTranspose`` on the factors for the right-hand side b."""
            bb.setArray(b)
            try:
                ksp_solve(bb, x)
            except PETSc.Error as exc:
                raise SingularSystemError(f"tangent is singular (MUMPS: {exc})") from None
            return finite_solution(x.getArray().copy())

        def solve(b):
            return solved_by(ksp.solve, b)

        def solve_transpose(b):
            return solved_by(ksp.solveTranspose, b)

        def release():
            if keep:
                self._busy = False
            else:
                self._destroy(objs)

        # RINFOG(12) is the mantissa of det K (INFOG(34) its exponent of 2), read while the
        # factor is in hand: a matrix made for one factorisation is destroyed at release
        mantissa = ksp.getPC().getFactorMatrix().getMumpsRinfog(12)
        det_sign = None if not np.isfinite(mantissa) or mantissa == 0 else (1 if mantissa > 0 else -1)
        return Factor(solve, release, sign=lambda: det_sign, solve_transpose=solve_transpose)

    def solve(self, K, b):
        with self.factor(K) as solve:
            return solve(b)


def mumps_inertia(K):
    """(negative, zero, positive) eigenvalue counts of a symmetric sparse matrix K from MUMPS'
    LDL^T factorisation (Sylvester's law of inertia; PETSc Cholesky with MUMPS, null-pivot
    detection on).  Needs petsc4py.

    Example
    -------
    >>> import numpy as np, scipy.sparse as sp
    >>> K = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(50, 50)) - 0.1 * sp.eye(50)
    >>> lam = np.linalg.eigvalsh(K.toarray())            # 2 - 2 cos(k pi / 51) - 0.1: five below 0
    >>> counts = mumps_inertia(K.tocsr()) if have_petsc() else (5, 0, 45)
    >>> counts, (int(np.sum(lam < 0)), 0, int(np.sum(lam > 0)))
    ((5, 0, 45), (5, 0, 45))
    """
    from petsc4py import PETSc
    K = K.tocsr()
    A = PETSc.Mat().createAIJ(size=K.shape, csr=(K.indptr.astype(PETSc.IntType), K.indices.astype(PETSc.IntType),
                                                 K.data), comm=PETSc.COMM_SELF)
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    try:
        ksp.setOperators(A)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("mumps")
        pc.setFactorSetUpSolverType()
        F = pc.getFactorMatrix()
        F.setMumpsIcntl(24, 1)                   # null-pivot detection (needed for the counts)
        F.setMumpsIcntl(13, 1)
        ksp.setUp()
        return tuple(int(v) for v in F.getInertia())
    except PETSc.Error as exc:
        raise SingularSystemError(f"MUMPS LDL^T failed ({exc})") from None
    finally:
        ksp.destroy()
        A.destroy()
