"""Sparse direct solvers for the (non-symmetric) tangent, and the one equilibrated factorisation
with iterative refinement that every solver uses.

``banded``: LAPACK's banded LU (dgbtrf) in a reverse Cuthill-McKee ordering, for the narrow
patterns of strips and beams, where SuperLU's set-up costs more than the factorisation.
``mumps``: PETSc/MUMPS LU through petsc4py (Debian's python3-petsc4py; with OpenBLAS it was
the fastest measured here, see ``benchmarks/``).  ``superlu``: SciPy's SuperLU with the
MMD_AT_PLUS_A ordering and diagonal pivoting on the equilibrated matrix (COLAMD fallback).
``auto`` picks, per pattern, the banded LU while n kl (kl + ku) <= BANDED_MAX_COST, else
SuperLU below AUTO_MUMPS_MIN unknowns and MUMPS above (when petsc4py imports): measured on this machine with checked_solve (equilibration, refinement,
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

from ..errors import OptionError, SingularSystemError
from .direct import (BandedSolver, CsrArrays, MumpsSolver, SuperLUSolver, available_solvers, have_petsc,
                     mumps_inertia)

__all__ = ["make_solver", "available_solvers", "checked_solve", "Factorization", "AUTO_MUMPS_MIN",
           "mumps_inertia", "BandedSolver", "BANDED_MAX_COST"]


# The probe's limit on |S K S|^-1 (S: the equilibration).  One random right-hand side alone
# measures it times the random vector's share of the null direction, ~ 1/sqrt(n): the clamped
# 6-element strip compressed exactly to its buckling load (cond 5e16) grew by 3.6e15 serially,
# 1.6e15 on one rank and 6.3e14 on two (MUMPS' round-off, other random vectors), so two ranks
# went on; the second solve (inverse iteration) grows by 5.8e16 / 8.9e15 / 7.3e15.
PROBE_GROWTH = 1e15


class Factorization:
    """The equilibrated factorisation of K (sparse: the project's solver; dense: LAPACK LU).

    ``solve(b)`` returns x with K x = b (``solve(b, transpose=True)``: K^T x = b on the same
    factors, S K^T S being the transpose of S K S): S K S y = S b is solved, then refined while the
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
        self.Ks = CsrArrays(data, K.indices, K.indptr, K.shape)
        self.knorm = float(np.max(np.add.reduceat(np.abs(data), K.indptr[:-1]))) if len(data) else 0.0
        self._knorm_t = None
        self._ctx = solver.factor(self.Ks)
        self._solve = self._ctx.__enter__()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _berr(self, bs, y, transpose=False):
        Ky = (self.s * y) @ self.K if transpose else self.K @ (self.s * y)      # K^T v = (v^T K)^T
        rs = bs - self.s * Ky                                   # S b - S K S y (or S K^T S y)
        # |S K^T S|_inf = |S K S|_1: the transposed solve's norm
        knorm = self.knorm_t if transpose else self.knorm
        return rs, np.linalg.norm(rs) / (knorm * np.linalg.norm(y) + np.linalg.norm(bs) + 1e-300)

    @property
    def knorm_t(self):
        """|S K S|_1 (the infinity norm of the transpose), computed at its first use."""
        if self._knorm_t is None:
            self._knorm_t = float(np.max(np.bincount(self.Ks.indices, np.abs(self.Ks.data), self.Ks.shape[1]))) \
                if len(self.Ks.data) else 0.0
        return self._knorm_t

    def solve(self, b, transpose=False, check=True):
        """x with K x = b, or K^T x = b with ``transpose`` (see the class docstring); b (N,) or
        (N, k) (k right-hand sides, solved one by one on the same factorisation).  ``check=False``
        skips the refinement and the backward-error check (only a non-finite solution raises):
        for an iteration that tests its answer on the true residual (``control.corrector``)."""
        if self.dense:
            return sla.lu_solve(self.lu, b, trans=1 if transpose else 0)
        b = np.asarray(b, dtype=float)
        if b.ndim == 2:
            return np.column_stack([self.solve(b[:, j], transpose, check) for j in range(b.shape[1])]) \
                if b.shape[1] else np.zeros_like(b)
        back = self._solve
        if transpose:
            back = self._ctx.solve_transpose
            if back is None:
                raise OptionError("this linear solver has no transposed solve (the built-in ones have)")
        bs = self.s * b
        y = back(bs)
        if not check:
            return self.s * y
        rs, berr = self._berr(bs, y, transpose)
        for _ in range(2):                                   # iterative refinement
            if not np.isfinite(berr) or berr <= 4 * _EPS:
                break
            y2 = y + back(rs)
            rs2, berr2 = self._berr(bs, y2, transpose)
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
        """Raise SingularSystemError if a random right-hand side grows by more than 1e15 (the
        larger growth of two solves: a random b, then its normalised solution -- one step of
        inverse iteration, :data:`PROBE_GROWTH`)."""
        if self.dense:
            return
        br = np.random.default_rng(12345).standard_normal(self.Ks.shape[0])
        yr = self._solve(br)
        growth = np.linalg.norm(yr) / np.linalg.norm(br)
        if np.isfinite(growth) and growth > 0:
            growth = max(growth, np.linalg.norm(self._solve(yr / np.linalg.norm(yr))))
        if not np.isfinite(growth) or growth > PROBE_GROWTH:
            raise SingularSystemError(f"tangent is singular or nearly so (solution growth "
                                      f"{growth:.1e} for a random right-hand side)")

    def det_sign(self):
        """+1 or -1: the sign of det K from the factors in hand (None when a pivot is zero or
        the solver cannot tell); valid after ``close()`` until the solver factors again.

        Example
        -------
        >>> import numpy as np, scipy.sparse as sp
        >>> K = sp.csr_matrix(np.diag([2.0, -1.0, 3.0]))
        >>> with Factorization(K, make_solver("banded")) as F:
        ...     pass
        >>> F.det_sign(), Factorization(K.toarray(), None).det_sign()
        (-1, -1)
        """
        if self.dense:
            lu, piv = self.lu
            swaps = np.count_nonzero(piv != np.arange(len(piv)))
            neg = np.count_nonzero(np.diag(lu) < 0) + swaps
            return -1 if neg % 2 else 1
        return self._ctx.sign()

    def close(self):
        if not self.dense:
            self._ctx.__exit__(None, None, None)


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


AUTO_MUMPS_MIN = 2000   # unknowns from which "auto" uses MUMPS (see the module docstring)
BANDED_MAX_COST = 5e7   # n kl (kl + ku) up to which "auto" uses the banded LU
BANDED_MAX_N = 50_000   # beyond this many unknowns "auto" does not look for a band


class AutoSolver:
    """The banded LU for narrow patterns (strips, beams: ``BANDED_MAX_COST``), else SuperLU
    for small tangents and MUMPS for large ones (the choice depends on the pattern only, so a
    run and its resumption factor the same matrices the same way).

    Measured (``benchmarks/speed.py``, factorisation with refinement): the banded LU is 2.2-2.4x
    faster than SuperLU on 1-element-wide strips (192-2400 unknowns), 1.4-2x on 20x2-20x6 and
    10x10 plates (cost 1e6-2e7), even at 16x16 (1.2e8) and 0.6x at 30x30 (1.4e9)."""
    name = "auto"

    def __init__(self):
        self._small = SuperLUSolver()
        self._band = BandedSolver()
        self._large = None            # MUMPS, made (and petsc4py imported) at the first large matrix

    def choice(self, K):
        """'banded', 'superlu' or 'mumps': the solver this pattern gets."""
        n = K.shape[0]
        if n <= BANDED_MAX_N:
            lay = self._band.layout(K)
            if lay.cost <= BANDED_MAX_COST:
                return "banded"
            lay.release()                      # a wide pattern keeps only its verdict
        return "superlu" if n < AUTO_MUMPS_MIN or not have_petsc() else "mumps"

    def factor(self, K):
        if not (isinstance(K, CsrArrays) or sp.isspmatrix_csr(K)):
            K = K.tocsr()
        which = self.choice(K)
        if which == "banded":
            return self._band.factor(K)
        if which == "superlu":
            return self._small.factor(K)
        if self._large is None:
            self._large = MumpsSolver()
        return self._large.factor(K)

    def solve(self, K, b):
        with self.factor(K) as solve:
            return solve(b)


def make_solver(name="auto"):
    """The linear solver ``name`` ('auto', 'banded', 'superlu' or 'mumps').

    Parameters
    ----------
    name : str, optional
        'auto' (the banded LU for narrow patterns, else SuperLU below AUTO_MUMPS_MIN unknowns and
        MUMPS above when available), 'banded', 'superlu' or 'mumps' (needs petsc4py).

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
    if name == "banded":
        return BandedSolver()
    if name == "mumps":
        if not have_petsc():
            raise OptionError("solver 'mumps' needs petsc4py (Debian: python3-petsc4py); use 'superlu'")
        return MumpsSolver()
    raise OptionError(f"unknown linear solver {name!r}; choose auto, banded, mumps or superlu")
