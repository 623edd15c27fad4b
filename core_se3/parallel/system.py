"""The distributed linear algebra of one rank: the tangent as a PETSc MPIAIJ matrix filled by COO
from the local CSR data, the ghost exchanges of nodal arrays, global norms, and the linear
solvers (MUMPS, or a Krylov method with GAMG or BoomerAMG), all through PETSc.

Layout.  Every node keeps its six dofs in the distributed vectors (block size 6, nodes in the
numbering of ``partition``: rank after rank); a dof that a support holds is an identity row
and column (right-hand side zero), so the free block is the serial K_ff and the multigrid
solvers see whole nodes.  On several ranks the local Problem's CSR (free dofs of the local
nodes) maps entry by entry into COO positions (``setPreallocationCOO`` once); each iteration
hands its data to ``MatSetValuesCOO``, which sums the entries that several ranks hold.  On one
rank the kernels' CSR of all dofs is PETSc's matrix (``matrix.SharedCsrMatrix``: no copy),
its held rows and columns made identity in place.

Solve.  As the serial ``solvers.linalg.Factorization``: the symmetric diagonal equilibration
S K S (S = |diag K|^-1/2), then

* ``mumps``: LU (distributed MUMPS; its analysis reused while the pattern stays), two steps of
  iterative refinement and the backward-error test; the first solve of a run also checks the
  growth of a random right-hand side (a missing support);
* ``gamg``: GMRES (or the KSP of ``ksp_type``) with smoothed-aggregation AMG, whose near-null
  space is the six rigid-body modes of the current configuration (``rigid_body_modes``, scaled
  by S^-1 for the equilibrated system);
* ``hypre``: GMRES with BoomerAMG (nodal coarsening on the 6-dof blocks).

Free-form PETSc options (``petsc_options``, e.g. {"ksp_rtol": 1e-12}) are set under this
system's prefix ``core_se3_`` and override the defaults.
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..errors import LinearSolverError, OptionError, ParallelError, SingularSystemError
from ..solvers.linalg import PROBE_GROWTH
from ..solvers.stability import ASYM_TOL
from .comm import petsc_comm
from .matrix import CooMatrix, SharedCsrMatrix

__all__ = ["LINEAR", "DistributedSystem", "rigid_body_modes"]

LINEAR = ("mumps", "gamg", "hypre")
_EPS = np.finfo(float).eps

_DEFAULTS = {
    # ICNTL(33): MUMPS' determinant (its sign: load control's stability check, limit_check)
    "mumps": {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps", "mat_mumps_icntl_33": 1},
    "gamg": {"ksp_type": "gmres", "ksp_gmres_restart": 100, "ksp_gmres_modifiedgramschmidt": True, "ksp_rtol": 1e-10, "ksp_atol": 0.0, "ksp_max_it": 2000,
             "pc_type": "gamg", "pc_gamg_type": "agg", "pc_gamg_agg_nsmooths": 1, "pc_gamg_threshold": 0.02,
             "pc_gamg_reuse_interpolation": True, "mg_levels_ksp_type": "chebyshev",
             "mg_levels_pc_type": "jacobi", "mg_levels_ksp_max_it": 3},
    "hypre": {"ksp_type": "gmres", "ksp_gmres_restart": 100, "ksp_gmres_modifiedgramschmidt": True, "ksp_rtol": 1e-10, "ksp_atol": 0.0, "ksp_max_it": 2000,
              "pc_type": "hypre", "pc_hypre_type": "boomeramg", "pc_hypre_boomeramg_nodal_coarsen": 6,
              "pc_hypre_boomeramg_vec_interp_variant": 0, "pc_hypre_boomeramg_strong_threshold": 0.5},
}


def rigid_body_modes(g, ell=1.0):
    """The six rigid-body modes at the frames g (n, 4, 4) as body-frame twists (n, 6, 6):
    column k is the increment eta_i = Ad_{g_i^-1} xi_k of node i under the lab twist xi_k
    about the centroid c (k < 3: translation e_k; k >= 3: rotation about e_k scaled by ell).

    A superposed rigid motion h g_i = g_i exp(eta_i) gives eta_i = Ad_{g_i^-1} xi: for a
    rotation about e through c, eta_v = R_i^T (e x (x_i - c)) (the lab velocity of node i,
    in its body frame) and eta_w = R_i^T e; a translation gives (R_i^T e, 0).  The left-
    trivialised tangent K of a free, unloaded shell annihilates them.

    Parameters
    ----------
    g : (n, 4, 4) array
        Nodal frames.
    ell : float, optional
        Length that scales the rotations (the problem's length scale: modes of like size).

    Returns
    -------
    (n, 6, 6) ndarray

    Example
    -------
    >>> import numpy as np
    >>> g = np.broadcast_to(np.eye(4), (2, 4, 4)).copy(); g[1, 0, 3] = 2.0     # nodes at x = 0, 2
    >>> N = rigid_body_modes(g)
    >>> N[1, :3, 5].tolist(), N[1, 3:, 5].tolist()                 # rotation about z: node 1 moves +y
    ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])
    """
    g = np.asarray(g, float)
    c = g[:, :3, 3].mean(0)
    h = np.eye(4)
    h[:3, 3] = -c
    modes = lie.Ad(lie.inv(g) @ np.linalg.inv(h))
    modes[:, :, 3:] *= ell
    return modes


def _dot_scaled(a, b, ell):
    """sum of a . b with moment-like components / ell^2 ((n, 6) arrays)."""
    return float(np.sum(a[:, :3] * b[:, :3]) + np.sum(a[:, 3:] * b[:, 3:]) / ell ** 2)


class DistributedSystem:
    """The PETSc objects of a distributed Newton run on one rank (module docstring).

    Parameters
    ----------
    comm : mpi4py.MPI.Comm
        The ranks.
    sub : core_se3.parallel.local.Subdomain
        This rank's share.
    free : (n_loc, 6) bool array
        The free dofs of the local nodes (the local Problem's).
    indptr, indices : arrays
        The CSR structure of the local tangent (``Pattern``/``Assembler``).
    linear : str, optional
        'mumps' (default), 'gamg' or 'hypre'.
    petsc_options : dict, optional
        PETSc options without the leading dash (override the defaults of ``linear``).
    shared : bool, optional
        One rank whose ``indptr``/``indices`` are the CSR of all its dofs (held ones included):
        PETSc's matrix shares them (``matrix.SharedCsrMatrix``, no copy) instead of being
        filled through COO from the free dofs' CSR.

    Example
    -------
    The PETSc objects need petsc4py; the layout does not:

    >>> LINEAR
    ('mumps', 'gamg', 'hypre')
    """

    def __init__(self, comm, sub, free, indptr, indices, linear="mumps", petsc_options=None, shared=False):
        from petsc4py import PETSc
        if linear not in LINEAR:
            raise ParallelError(f"unknown linear solver {linear!r}; choose one of {', '.join(LINEAR)}")
        self.PETSc, self.comm, self.sub, self.linear = PETSc, comm, sub, linear
        self.pcomm = pcomm = petsc_comm(comm)        # the run's ranks (a sub-communicator too)
        n_own, n = sub.n_owned, len(sub.owner)
        self.n_own = n_own
        free = np.asarray(free, bool).reshape(-1, 6)
        self.shared = bool(shared)
        if self.shared:                  # one rank, a pattern of all dofs: PETSc's matrix is its CSR
            if comm.size != 1 or len(indptr) != 6 * n + 1:
                raise ParallelError("a shared matrix needs one rank and a pattern of all dofs")
            self.K = SharedCsrMatrix(indptr, indices, ~free.ravel(), bsize=6)
            self.values = self.K.data
            self.nnz_local = len(self.values)
        else:
            gnode = sub.index[sub.nodes]                                    # distributed node ids
            gdof = (6 * gnode[:, None] + np.arange(6)).ravel()[free.ravel()]   # local free dof -> global
            rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
            held = ~free[:n_own]
            hdof = (6 * gnode[:n_own, None] + np.arange(6))[held]
            self.nnz_local = int(indptr[-1])
            self.values = np.zeros(self.nnz_local + len(hdof))
            self.values[self.nnz_local:] = 1.0                             # identity rows of held dofs
            self.K = CooMatrix(pcomm, 6 * n_own, 6 * n, np.concatenate([gdof[rows], hdof]),
                               np.concatenate([gdof[np.asarray(indices)], hdof]), bsize=6)
            del rows
        self.free_own = free[:n_own]
        ghosts = np.asarray(sub.ghost_index, dtype=PETSc.IntType)
        self.x = PETSc.Vec().createGhost(ghosts, size=(6 * n_own, 6 * n), bsize=6, comm=pcomm)
        self.b = self.x.duplicate()
        self.y = self.x.duplicate()
        self.s = self.x.duplicate()
        self.nodal = PETSc.Vec().createGhost(ghosts, size=(12 * n_own, 12 * n), bsize=12, comm=pcomm)
        self.frames = PETSc.Vec().createGhost(ghosts, size=(16 * n_own, 16 * n), bsize=16, comm=pcomm)
        self.ksp = PETSc.KSP().create(pcomm)
        self.ksp.setOptionsPrefix("core_se3_")
        opts = PETSc.Options()
        self._option_names = []
        for k, v in {**_DEFAULTS[linear], **(petsc_options or {})}.items():
            k = str(k).lstrip("-")
            opts[f"core_se3_{k}"] = ("true" if v else "false") if isinstance(v, bool) else v
            self._option_names.append(f"core_se3_{k}")
        try:
            self.ksp.setFromOptions()
        except PETSc.Error as exc:
            self._refused(exc, petsc_options or {}, _DEFAULTS[linear])
        self.probed = False
        self.scaled = False                # the matrix holds S K S (a solve equilibrated it in place)
        self.iterations = []               # Krylov iterations of every solve (iterative solvers)

    # ------------------------------------------------------------------ exchanges -------
    def sum_nodal(self, r_int, f_ext):
        """Owned sums (n_own, 6) of the local nodal forces (n_loc, 6) of every rank (reverse
        ghost update, ADD)."""
        PETSc = self.PETSc
        with self.nodal.localForm() as lf:
            a = lf.getArray(readonly=False).reshape(-1, 12)
            a[:, :6] = r_int
            a[:, 6:] = f_ext
        self.nodal.ghostUpdate(addv=PETSc.InsertMode.ADD_VALUES, mode=PETSc.ScatterMode.REVERSE)
        own = self.nodal.getArray(readonly=True).reshape(-1, 12)
        return own[:, :6].copy(), own[:, 6:].copy()

    def update_ghost_frames(self, g_loc):
        """Copy the owners' frames into the ghosts of ``g_loc`` (n_loc, 4, 4) (in place)."""
        PETSc = self.PETSc
        self.frames.setArray(g_loc[:self.n_own].reshape(-1))
        self.frames.ghostUpdate(addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.FORWARD)
        with self.frames.localForm() as lf:
            g_loc[self.n_own:] = lf.getArray(readonly=True).reshape(-1, 4, 4)[self.n_own:]
        return g_loc

    def _ghosted(self, vec):
        """(n_loc, 6) local form of a ghosted vector after the forward ghost update."""
        PETSc = self.PETSc
        vec.ghostUpdate(addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.FORWARD)
        with vec.localForm() as lf:
            return lf.getArray(readonly=True).reshape(-1, 6).copy()

    # ------------------------------------------------------------------ reductions ------
    def sumsq(self, *arrays, ell=1.0):
        """Global scaled squared norms of owned nodal arrays (n_own, 6) (moments / ell)."""
        loc = [_dot_scaled(a, a, ell) for a in arrays]
        return self.comm.allreduce(np.array(loc)) if self.comm.size > 1 else np.array(loc)

    def allsum(self, *values):
        v = np.array(values, float)
        return self.comm.allreduce(v) if self.comm.size > 1 else v

    # ------------------------------------------------------------------ solve -----------
    def assemble(self, data):
        """The tangent from the local CSR data (nnz_local,) (it may be ``values``' own view)."""
        if data is not None and not np.shares_memory(data, self.values):
            self.values[:self.nnz_local] = data
        self.scaled = False
        return self.K.set(self.values)

    def data_view(self):
        """A view of the matrix values that the local evaluation may write its CSR data into."""
        return self.values[:self.nnz_local]

    def _factor(self, g_loc=None, ell=1.0):
        """The symmetric equilibration S K S of the assembled tangent in place (S = |diag K|^-1/2),
        the multigrid's near-null space (g_loc: the local frames), the KSP set up; returns
        (the matrix, the diagonal of S).  SingularSystemError when the factorisation fails."""
        PETSc = self.PETSc
        A = self.K.mat
        d = A.getDiagonal()
        sa = np.abs(d.getArray(readonly=True))
        sa[sa == 0] = 1.0
        s = 1.0 / np.sqrt(sa)
        d.destroy()
        self.s.setArray(s)
        A.diagonalScale(self.s, self.s)                                   # S K S in place
        self.scaled = True
        if self.linear != "mumps" and g_loc is not None:
            self._near_null(g_loc, ell)
        self.ksp.setOperators(A)
        try:
            self.ksp.setUp()
        except PETSc.Error as exc:
            raise SingularSystemError(f"tangent is singular ({self.linear}: {exc})") from None
        return A, s

    def solve(self, rhs_own, g_loc=None, ell=1.0, probe=False):
        """eta (n_loc, 6) with K eta = rhs on the free dofs (rhs_own (n_own, 6), zero on held
        dofs), ghosts updated; the matrix must be assembled.  g_loc (the current local frames)
        gives the multigrid's near-null space.  SingularSystemError for a (near-)singular
        tangent, LinearSolverError when an iterative solver fails."""
        A, s = self._factor(g_loc, ell)
        bs = (s * np.where(self.free_own, rhs_own, 0.0).ravel())
        self.b.setArray(bs)
        y = self._apply(self.b, self.y)
        if self.linear == "mumps":
            y = self._refine(A, bs, y)
            if probe and not self.probed:
                self._probe()
        self.probed = True
        self.x.setArray(s * y)
        return self._ghosted(self.x)

    def solve_many(self, rhs_owns, transpose=False):
        """[eta (n_loc, 6)] with K eta = rhs (or K^T eta = rhs) for each rhs_own (n_own, 6) on one
        factorisation (the design's adjoint and direct sensitivities); the matrix must be
        assembled.  MUMPS only: the equilibrated S K S (or its transpose, S K^T S) is factored
        once, each solve refined as :meth:`solve`'s."""
        if self.linear != "mumps":
            raise ParallelError("several right-hand sides (design sensitivities) need linear = 'mumps'")
        A, s = self._factor()
        out = []
        for rhs in rhs_owns:
            bs = s * np.where(self.free_own, rhs, 0.0).ravel()
            self.b.setArray(bs)
            y = self._refine(A, bs, self._apply(self.b, self.y, transpose), transpose)
            self.x.setArray(s * y)
            out.append(self._ghosted(self.x))
        return out

    def _apply(self, b, out, transpose=False):
        PETSc = self.PETSc
        try:
            (self.ksp.solveTranspose if transpose else self.ksp.solve)(b, out)
        except PETSc.Error as exc:
            raise SingularSystemError(f"tangent is singular ({self.linear}: {exc})") from None
        reason = self.ksp.getConvergedReason()
        if self.linear != "mumps":
            self.iterations.append(int(self.ksp.getIterationNumber()))
            if reason < 0:
                raise LinearSolverError(f"{self.linear}: the Krylov solver stopped without converging "
                                        f"(reason {reason}, {self.ksp.getIterationNumber()} iterations, "
                                        f"residual {self.ksp.getResidualNorm():.2e})")
        y = out.getArray(readonly=True).copy()
        if not np.all(np.isfinite(y)):
            raise SingularSystemError("tangent is singular (non-finite solution)")
        return y

    def _refine(self, A, bs, y, transpose=False):
        """Two steps of iterative refinement with the backward-error test (as the serial
        Factorization), on the equilibrated system (or its transpose)."""
        PETSc = self.PETSc
        knorm = A.norm(PETSc.NormType.NORM_1 if transpose else PETSc.NormType.NORM_INFINITY)
        nb = np.sqrt(self.allsum(float(bs @ bs))[0])

        def berr(y):
            self.y.setArray(y)
            (A.multTranspose if transpose else A.mult)(self.y, self.x)
            rs = bs - self.x.getArray(readonly=True)
            sq = self.allsum(float(rs @ rs), float(y @ y))
            return rs, np.sqrt(sq[0]) / (knorm * np.sqrt(sq[1]) + nb + 1e-300)

        rs, e = berr(y)
        for _ in range(2):
            if not np.isfinite(e) or e <= 4 * _EPS:
                break
            self.b.setArray(rs)
            y2 = y + self._apply(self.b, self.y, transpose)
            rs2, e2 = berr(y2)
            if not e2 < e:
                break
            y, rs, improved, e = y2, rs2, e2 <= 0.5 * e, e2
            if not improved:
                break
        ny = np.sqrt(self.allsum(float(y @ y))[0])
        if not np.isfinite(e) or e > 1e-8 or ny > 1e15 * max(nb, 1e-300):
            raise SingularSystemError(f"tangent is singular or nearly so (backward error {e:.1e}, "
                                      f"solution growth {ny / max(nb, 1e-300):.1e})")
        return y

    def det_sign(self):
        """+1 or -1: the sign of det K of the last factorised tangent (MUMPS' determinant,
        ICNTL(33), of S K S: S > 0 keeps the sign; the held dofs' identity adds +1); None with
        an iterative solver, before a factorisation, or for a zero determinant."""
        if self.linear != "mumps" or not self.scaled:
            return None
        d = self.ksp.getPC().getFactorMatrix().getMumpsRinfog(12)
        return None if not np.isfinite(d) or d == 0 else (1 if d > 0 else -1)

    def negative_count(self, asym_tol=ASYM_TOL):
        """The number of negative eigenvalues of sym K on the free dofs (K: the assembled
        tangent, or the one the last solve factorised), counted on the ranks, never gathered:
        MUMPS' LDL^T of S sym(K) S (a congruence: the inertia of sym K; the held dofs' identity
        rows count as positive) gives its negative pivots, INFOG(12) (ICNTL(13) = 1: no
        ScaLAPACK root, whose pivots MUMPS does not count).  None, as serially
        (``solvers.stability.negative_count``), when the Jacobi-scaled skew part
        max |K_ij - K_ji| / sqrt(|K_ii K_jj|) exceeds asym_tol over the free rows outside the held
        nodes' diagonal blocks (non-conservative loads; ``solvers.stability.asymmetry``)."""
        PETSc = self.PETSc
        K = self.K.mat.duplicate(copy=True)
        if self.scaled:                                  # undo the solve's S K S on the copy
            inv = self.s.duplicate()
            inv.setArray(1.0 / self.s.getArray(readonly=True))
            K.diagonalScale(inv, inv)
            inv.destroy()
        d = K.getDiagonal()                              # Jacobi scaling (stability.asymmetry): a
        sa = np.abs(d.getArray(readonly=True))           # congruence, the inertia is kept
        top = sa.reshape(-1, 6).max(axis=0, initial=0.0)          # per component, as serially
        top = np.max(self.comm.allgather(top), axis=0) if self.comm.size > 1 else top
        d.setArray(1.0 / np.sqrt(np.maximum(sa, 1e-16 * np.tile(top, len(sa) // 6) + 1e-300)))
        K.diagonalScale(d, d)
        d.destroy()
        Kt = K.transpose(PETSc.Mat())                    # a new matrix: K.transpose() transposes K in
        skew = K.duplicate(copy=True)                    # place and returns K itself (K - K^T was 0,
        skew.axpy(-1.0, Kt)                              # a follower load's count not None, 2 K^T's)
        rows = self.free_own.ravel()
        held = np.repeat(~self.free_own.all(axis=1), 6)
        peak = [_free_rows_max(K, rows), _free_rows_max(skew, rows, held)]
        scale, asym = np.max(self.comm.allgather(peak), axis=0) if self.comm.size > 1 else peak
        pc = PETSc.PC().create(self.pcomm)
        try:
            if scale == 0 or asym > asym_tol:
                return None
            K.axpy(1.0, Kt)                              # K + K^T = 2 sym K
            return self._negative_pivots(K, pc)
        finally:
            for obj in (pc, skew, K, Kt):
                obj.destroy()

    def _negative_pivots(self, K, pc):
        """MUMPS' negative pivots of S K S (K symmetric, S = |diag K|^-1/2) through ``pc``."""
        PETSc = self.PETSc
        d = K.getDiagonal()
        sa = np.abs(d.getArray(readonly=True))
        sa[sa == 0] = 1.0
        d.setArray(1.0 / np.sqrt(sa))
        K.diagonalScale(d, d)
        d.destroy()
        K.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        try:
            pc.setOperators(K)
            pc.setType(PETSc.PC.Type.CHOLESKY)
            pc.setFactorSolverType("mumps")
            pc.setFactorSetUpSolverType()
            F = pc.getFactorMatrix()
            F.setMumpsIcntl(13, 1)
            pc.setUp()
            return int(F.getMumpsInfog(12))
        except PETSc.Error as exc:
            raise SingularSystemError(f"the symmetric tangent could not be factorised for its inertia ({exc})") from None

    def _probe(self):
        rng = np.random.default_rng(12345 + self.comm.rank)
        br = rng.standard_normal(6 * self.n_own)
        self.b.setArray(br)
        yr = self._apply(self.b, self.y)
        sq = self.allsum(float(yr @ yr), float(br @ br))
        growth = np.sqrt(sq[0] / sq[1])
        if np.isfinite(growth) and growth > 0:          # one step of inverse iteration (serially too:
            self.b.setArray(yr / np.sqrt(sq[0]))         # solvers.linalg.PROBE_GROWTH)
            y2 = self._apply(self.b, self.y)
            growth = max(growth, np.sqrt(self.allsum(float(y2 @ y2))[0]))
        if not np.isfinite(growth) or growth > PROBE_GROWTH:
            raise SingularSystemError(f"tangent is singular or nearly so (solution growth {growth:.1e} for a "
                                      "random right-hand side)")

    def _near_null(self, g_loc, ell):
        """Rigid-body modes of the owned nodes, zero on held dofs, times S^-1, orthonormalised."""
        PETSc = self.PETSc
        N = rigid_body_modes_global(g_loc[:self.n_own], self.comm, ell)     # about the global centroid
        N = N * self.free_own[:, :, None]
        sinv = 1.0 / self.s.getArray(readonly=True)
        vecs = []
        for k in range(6):
            v = self.x.duplicate()
            v.setArray(sinv * N[:, :, k].ravel())
            for w in vecs:
                v.axpy(-v.dot(w), w)
            nv = v.norm()
            if nv > 0:
                v.scale(1.0 / nv)
                vecs.append(v)
        ns = PETSc.NullSpace().create(vectors=vecs, comm=self.pcomm)
        self.K.mat.setNearNullSpace(ns)
        for v in vecs:
            v.destroy()
        ns.destroy()

    def _refused(self, exc, user, defaults):
        """PETSc refused the options (the same on every rank): an OptionError naming the user's
        option it refuses (each tried alone on a scratch solver) and PETSc's reason, instead of
        a PETSc traceback on every rank."""
        PETSc = self.PETSc
        reason = [ln.strip() for ln in str(exc).splitlines() if ln.strip()][-1:] or [f"error code {exc.ierr}"]
        comm = self.ksp.getComm()
        self.destroy()
        culprit = None
        for k, v in user.items():
            k = str(k).lstrip("-")
            opts = PETSc.Options()
            trial = {**{str(d).lstrip("-"): x for d, x in defaults.items()}, k: v}    # the linear solver's own, and k
            for name, x in trial.items():
                opts[f"core_se3_probe_{name}"] = ("true" if x else "false") if isinstance(x, bool) else x
            ksp = PETSc.KSP().create(comm)
            ksp.setOptionsPrefix("core_se3_probe_")
            try:
                ksp.setFromOptions()
            except PETSc.Error as err:
                if culprit is None:
                    culprit = (k, v)
                    reason = [ln.strip() for ln in str(err).splitlines() if ln.strip()][-1:] or reason
            finally:
                ksp.destroy()
                for name in trial:
                    opts.delValue(f"core_se3_probe_{name}")
        what = f"the option {culprit[0]} = {culprit[1]!r}" if culprit else f"the options {dict(user)!r}"
        err = OptionError(f"PETSc refused {what} ({reason[0].lstrip('[0123456789] ')}); see the PETSc manual "
                          "for the option's values (docs/PARALLEL.md)")
        err.param = None if culprit is None else f"petsc.{culprit[0]}"
        raise err from None

    def destroy(self):
        opts = self.PETSc.Options()
        for k in self._option_names:
            opts.delValue(k)
        for obj in (self.ksp, self.x, self.b, self.y, self.s, self.nodal, self.frames):
            obj.destroy()
        self.K.destroy()


def _free_rows_max(A, rows, held=None):
    """max |A_ij| over this rank's rows of A where ``rows`` (bool, the owned dofs) is set; with
    ``held`` (bool per owned dof: its node is held by a support) not in a held node's diagonal
    block (``solvers.stability.asymmetry``: the reactions' skew term lives there)."""
    indptr, cols, values = A.getValuesCSR()
    counts = np.diff(indptr)
    keep = np.repeat(rows, counts)
    if held is not None:
        row = A.getOwnershipRange()[0] + np.repeat(np.arange(len(counts)), counts)
        keep &= ~(np.repeat(held, counts) & (cols // 6 == row // 6))
    return float(np.abs(values[keep]).max()) if np.any(keep) else 0.0


def rigid_body_modes_global(g_own, comm, ell=1.0):
    """:func:`rigid_body_modes` of the owned frames about the centroid of all ranks' nodes.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3.parallel.comm import SerialComm
    >>> g = np.broadcast_to(np.eye(4), (2, 4, 4)).copy(); g[1, 0, 3] = 2.0
    >>> bool(np.allclose(rigid_body_modes_global(g, SerialComm()), rigid_body_modes(g)))
    True
    """
    s = comm.allreduce(np.r_[g_own[:, :3, 3].sum(0), len(g_own)]) if comm.size > 1 else \
        np.r_[g_own[:, :3, 3].sum(0), len(g_own)]
    c = s[:3] / max(s[3], 1)
    h = np.eye(4)
    h[:3, 3] = -c
    modes = lie.Ad(lie.inv(g_own) @ np.linalg.inv(h))
    modes[:, :, 3:] *= ell
    return modes
