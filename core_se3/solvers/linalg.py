"""Sparse direct solvers for the (non-symmetric) tangent, and the one equilibrated factorisation
with iterative refinement that every solver uses.

``mumps``: PETSc/MUMPS LU through petsc4py (Debian's python3-petsc4py; with OpenBLAS it was
the fastest measured here, see ``benchmarks/``).  ``superlu``: SciPy's SuperLU with the
MMD_AT_PLUS_A ordering and diagonal pivoting on the equilibrated matrix (COLAMD fallback).
``auto`` picks, per matrix, SuperLU below AUTO_MUMPS_MIN unknowns and MUMPS above (when
petsc4py imports): measured on this machine with checked_solve (equilibration, refinement,
backward-error check) SuperLU took 3.3 / 16 ms against MUMPS' 6.4 / 22 ms at 480 / 1583
unknowns, and MUMPS was faster from ~2500 (26 vs 41 ms) to 13967 unknowns (261 vs 450 ms),
where PETSc's set-up cost no longer dominates.

:class:`Factorization` factors S K S once (S = |diag K|^-1/2, symmetric diagonal
equilibration: at L/h = 1e4 membrane and bending stiffnesses differ by ~1e10 and unscaled
pivoting loses digits) and solves with two steps of iterative refinement and a backward-error
check, so that a (near-)singular tangent that the factorisation let through is reported, never
returned as an answer.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import OptionError, SingularSystemError

__all__ = ["make_solver", "available_solvers", "checked_solve", "Factorization", "AUTO_MUMPS_MIN",
           "mumps_inertia"]


class Factorization:
    """The equilibrated factorisation of K (sparse: the project's solver; dense: LAPACK LU).

    ``solve(b)`` returns x with K x = b: S K S y = S b is solved, then refined while the
    normwise backward error |S b - S K S y| / (|S K S|_inf |y| + |S b|) is above 4 eps and
    falls by half per step (at most twice, LAPACK's rule); SingularSystemError when it stays
    above 1e-8 or the solution grows more than 1e15 x b.  ``probe()`` raises
    SingularSystemError when a random right-hand side grows by 1e15 (a load may not excite an
    unrestrained mode; a random one does).  Use as a context manager or call ``close()``.

    Parameters
    ----------
    K : scipy.sparse matrix or (N, N) array
        The (non-symmetric) tangent.
    solver : object
        A linear solver of :func:`make_solver` (ignored for a dense K).

    Example
    -------
    >>> import numpy as np, scipy.sparse as sp
    >>> K = sp.csr_matrix(np.array([[4.0, 1.0], [2.0, 3.0]]))
    >>> with Factorization(K, make_solver("superlu")) as F:
    ...     np.round(F.solve(np.array([1.0, 2.0])), 12).tolist()
    [0.1, 0.6]
    """

    def __init__(self, K, solver):
        self.dense = not sp.issparse(K)
        if self.dense:
            K = np.asarray(K, float)
            try:
                with np.errstate(all="raise"):
                    self.lu = sla.lu_factor(K, check_finite=True)
            except (FloatingPointError, ValueError, sla.LinAlgError) as exc:
                raise SingularSystemError(f"tangent is singular ({exc})") from None
            if np.any(np.abs(np.diag(self.lu[0])) < 1e-14 * np.abs(K).max()):
                raise SingularSystemError("tangent is singular (zero pivot)")
            self.K = K
            return
        K = K.tocsr()
        d = np.abs(K.diagonal())
        d[d == 0] = 1.0
        self.s = 1.0 / np.sqrt(d)
        rows = _row_indices(K.indptr)
        # S K S on the same structure (no sparse products): entry (i, j) times s_i s_j, handed
        # to the solver as bare CSR arrays (no second scipy matrix per factorisation)
        data = K.data * (self.s[rows] * self.s[K.indices])
        self.K = K
        self.Ks = _CsrArrays(data, K.indices, K.indptr, K.shape)
        self.knorm = float(np.max(np.add.reduceat(np.abs(data), K.indptr[:-1]))) if len(data) else 0.0
        self._ctx = solver.factor(self.Ks)
        self._solve = self._ctx.__enter__()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _berr(self, bs, y):
        rs = bs - self.s * (self.K @ (self.s * y))              # S b - S K S y
        return rs, np.linalg.norm(rs) / (self.knorm * np.linalg.norm(y) + np.linalg.norm(bs) + 1e-300)

    def solve(self, b):
        """x with K x = b (see the class docstring); b (N,) or (N, k) (k right-hand sides,
        solved one by one on the same factorisation)."""
        if self.dense:
            return sla.lu_solve(self.lu, b)
        b = np.asarray(b, dtype=float)
        if b.ndim == 2:
            return np.column_stack([self.solve(b[:, j]) for j in range(b.shape[1])]) if b.shape[1] \
                else np.zeros_like(b)
        bs = self.s * b
        y = self._solve(bs)
        rs, berr = self._berr(bs, y)
        for _ in range(2):                                   # iterative refinement
            if not np.isfinite(berr) or berr <= 4 * _EPS:
                break
            y2 = y + self._solve(rs)
            rs2, berr2 = self._berr(bs, y2)
            if not berr2 < berr:
                break
            y, rs, improved = y2, rs2, berr2 <= 0.5 * berr
            berr = berr2
            if not improved:
                break
        # a backward-stable LU always has a small backward error, so near-singularity shows up as
        # |y| >> |b_s| (pivots at round-off level), which is what a missing support produces.
        ny, nb = np.linalg.norm(y), max(np.linalg.norm(bs), 1e-300)
        if not np.isfinite(berr) or berr > 1e-8 or ny > 1e15 * nb:
            raise SingularSystemError(f"tangent is singular or nearly so (backward error "
                                      f"{berr:.1e}, solution growth {ny / nb:.1e})")
        return self.s * y

    def probe(self):
        """Raise SingularSystemError if a random right-hand side grows by more than 1e15."""
        if self.dense:
            return
        br = np.random.default_rng(12345).standard_normal(self.Ks.shape[0])
        yr = self._solve(br)
        growth = np.linalg.norm(yr) / np.linalg.norm(br)
        if not np.isfinite(growth) or growth > 1e15:
            raise SingularSystemError(f"tangent is singular or nearly so (solution growth "
                                      f"{growth:.1e} for a random right-hand side)")

    def close(self):
        if not self.dense:
            self._ctx.__exit__(None, None, None)


class _CsrArrays:
    """The arrays of a CSR matrix (data, indices, indptr, shape) without a scipy object: what
    the solvers' ``factor`` reads (``tocsr()`` returns itself)."""
    __slots__ = ("data", "indices", "indptr", "shape")

    def __init__(self, data, indices, indptr, shape):
        self.data, self.indices, self.indptr, self.shape = data, indices, indptr, tuple(shape)

    def tocsr(self):
        return self


_EPS = np.finfo(float).eps
_ROWS = {}


def _row_indices(indptr):
    """The row of every stored entry of a CSR structure (cached per structure array)."""
    key = (id(indptr), len(indptr), int(indptr[-1]))
    hit = _ROWS.get(key)
    if hit is not None and hit[0] is indptr:
        return hit[1]
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    if len(_ROWS) > 8:
        _ROWS.clear()
    _ROWS[key] = (indptr, rows)
    return rows


def checked_solve(solver, K, b, probe=False):
    """Solve K x = b once through a :class:`Factorization` (with ``probe``: also test the
    factor with a random right-hand side, as for the first solve of a path).

    Parameters
    ----------
    solver : object
        From :func:`make_solver`.
    K : scipy.sparse matrix or array
        The matrix; b : (N,) the right-hand side.
    probe : bool, optional
        Also run :meth:`Factorization.probe`.

    Returns
    -------
    (N,) ndarray
        x; a (near-)singular K raises :class:`~core_se3.errors.SingularSystemError`.

    Example
    -------
    >>> import numpy as np, scipy.sparse as sp
    >>> checked_solve(make_solver("superlu"), sp.csr_matrix([[2.0, 0.0], [0.0, 4.0]]), np.array([2.0, 2.0])).tolist()
    [1.0, 0.5]
    >>> checked_solve(make_solver("superlu"), sp.csr_matrix([[1.0, 1.0], [1.0, 1.0]]), np.ones(2))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.SingularSystemError: tangent is singular...
    """
    with Factorization(K, solver) as F:
        x = F.solve(b)
        if probe:
            F.probe()
    return x


def _have_petsc():
    """petsc4py is installed (found without importing it: the import costs ~0.5 s)."""
    import importlib.util
    return importlib.util.find_spec("petsc4py") is not None


def available_solvers():
    """The linear solvers this installation has.

    Returns
    -------
    list of str
        'superlu' always, 'mumps' when petsc4py imports.

    Example
    -------
    >>> "superlu" in available_solvers()
    True
    """
    return ["superlu"] + (["mumps"] if _have_petsc() else [])


class _Factor:
    """Context manager holding a factorisation; calling it solves for one right-hand side."""

    def __init__(self, solve, release=lambda: None):
        self._solve, self._release = solve, release

    def __enter__(self):
        return self._solve

    def __exit__(self, *exc):
        self._release()
        return False


def _finite(x):
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
        if isinstance(K, _CsrArrays) or sp.isspmatrix_csr(K):
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
        return _Factor(lambda b: _finite(lu.solve(b, trans=trans)))

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
        ksp.setErrorIfNotConverged(True)
        objs = (indptr, indices, A, ksp, A.createVecLeft(), A.createVecRight(), data)
        return objs, False

    @staticmethod
    def _destroy(objs):
        for obj in objs[2:6]:
            obj.destroy()

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

        def solve(b):
            bb.setArray(b)
            try:
                ksp.solve(bb, x)
            except PETSc.Error as exc:
                raise SingularSystemError(f"tangent is singular (MUMPS: {exc})") from None
            return _finite(x.getArray().copy())

        def release():
            if keep:
                self._busy = False
            else:
                self._destroy(objs)

        return _Factor(solve, release)

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
    >>> counts = mumps_inertia(K.tocsr()) if _have_petsc() else (5, 0, 45)
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


AUTO_MUMPS_MIN = 2000   # unknowns from which "auto" uses MUMPS (see the module docstring)


class AutoSolver:
    """SuperLU for small tangents, MUMPS for large ones (the choice depends on the size only,
    so a run and its resumption factor the same matrices the same way)."""
    name = "auto"

    def __init__(self):
        self._small = SuperLUSolver()
        self._large = None            # MUMPS, made (and petsc4py imported) at the first large matrix

    def factor(self, K):
        if K.shape[0] < AUTO_MUMPS_MIN:
            return self._small.factor(K)
        if self._large is None:
            self._large = MumpsSolver() if _have_petsc() else self._small
        return self._large.factor(K)

    def solve(self, K, b):
        with self.factor(K) as solve:
            return solve(b)


def make_solver(name="auto"):
    """The linear solver ``name`` ('auto', 'superlu' or 'mumps').

    Parameters
    ----------
    name : str, optional
        'auto' (SuperLU below AUTO_MUMPS_MIN unknowns, MUMPS above when available), 'superlu' or
        'mumps' (needs petsc4py).

    Returns
    -------
    object
        A solver with ``factor(K)`` (a context manager yielding solve(b)) and ``solve(K, b)``.
        OptionError for an unknown or unavailable name.

    Example
    -------
    >>> make_solver("superlu").name, make_solver().name
    ('superlu', 'auto')
    """
    if name == "auto":
        return AutoSolver()
    if name == "superlu":
        return SuperLUSolver()
    if name == "mumps":
        if not _have_petsc():
            raise OptionError("solver 'mumps' needs petsc4py (Debian: python3-petsc4py); use 'superlu'")
        return MumpsSolver()
    raise OptionError(f"unknown linear solver {name!r}; choose auto, mumps or superlu")
