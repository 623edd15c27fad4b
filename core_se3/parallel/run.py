"""The set-up of a distributed run (partition, this rank's share and local Problem, the PETSc
system) and what the Newton driver asks of it: evaluations whose residual, norms and tangent
are global, solves, exponential updates with ghost frames, and gathers of whole-mesh arrays
for the step records.

Every rank holds the whole Problem (its definition: mesh, loads, supports -- not its element,
which is built per rank on the rank's elements), its own frames (owned nodes and ghosts), and
after each stored step the gathered frames of the whole mesh (the step records, probes,
reactions and checkpoints are the serial ones).
"""
from __future__ import annotations

import numpy as np

from ..errors import ParallelError
from ..model.base import conservative_loads
from .comm import collective, world
from .local import PatternAssembler, local_problem, subdomain
from .localize import localize_load
from .partition import check_partition, partition_elements

__all__ = ["DistributedRun", "GlobalEvaluation", "release_memory"]

STAGGER_ABOVE = 20_000     # local elements from which the ranks build their elements one at a time


def release_memory(threshold=1 << 20):
    """Hand freed heap memory back to the system (glibc: ``mallopt(M_MMAP_THRESHOLD)`` so that
    arrays above ``threshold`` bytes are mapped and unmapped on their own, then
    ``malloc_trim(0)``); a no-op elsewhere.  In a multi-threaded MPI process glibc otherwise keeps
    the set-up's temporaries (element data, pattern, COO sort): 3-4x the memory that stays.

    Example
    -------
    >>> release_memory() in (True, False)
    True
    """
    import ctypes
    import ctypes.util
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.mallopt(-3, int(threshold))          # M_MMAP_THRESHOLD (fixed: no dynamic growth)
        libc.malloc_trim(0)
        return True
    except (OSError, AttributeError):
        return False


def _threads_per_rank(size):
    """numba threads of this rank: NUMBA_NUM_THREADS if set, else 1 with several ranks (the
    ranks already share the cores); set in numba and returned."""
    import os
    import numba
    if size > 1 and not os.environ.get("NUMBA_NUM_THREADS"):
        numba.set_num_threads(1)
    return numba.get_num_threads()


class GlobalEvaluation:
    """The equations at one state, summed over the ranks (owned nodes of this rank).

    Attributes
    ----------
    r_int, f_ext : (n_own, 6) ndarray
        Internal and external nodal forces of the owned nodes (all ranks' parts summed).
    r : (n_own, 6) ndarray
        r_int - f_ext on the free dofs, zero on held ones.
    rn, floor : float
        The relative residual and its round-off floor (global, as ``solvers.convergence``).
    force_scale, energy : float
        Global.
    local : core_se3.model.Evaluation
        The local Problem's evaluation (stresses of this rank's elements, linearisation).

    Example
    -------
    >>> GlobalEvaluation.__name__
    'GlobalEvaluation'
    """

    def __init__(self, r_int, f_ext, r, rn, floor, force_scale, energy, local):
        self.r_int, self.f_ext, self.r = r_int, f_ext, r
        self.rn, self.floor, self.force_scale, self.energy, self.local = rn, floor, force_scale, energy, local

    @property
    def stress(self):
        return self.local.stress


class DistributedRun:
    """One rank's part of a distributed run of ``problem`` (module docstring).

    Parameters
    ----------
    problem : core_se3.Problem
        The whole problem (the same definition on every rank).
    comm : mpi4py.MPI.Comm, optional
        Default :func:`comm.world`.
    linear : str, optional
        'mumps', 'gamg' or 'hypre' (``system.DistributedSystem``).
    petsc_options : dict, optional
        Free-form PETSc options.
    partition : str or (m,) array, optional
        A partitioner name (``partition.PARTITIONERS``) or the rank of every element (e.g. from
        a checkpoint).

    Example
    -------
    The set-up needs petsc4py (``mpirun -n 2 python script.py``, docs/PARALLEL.md):

    >>> DistributedRun.__name__
    'DistributedRun'
    """

    def __init__(self, problem, comm=None, linear="mumps", petsc_options=None, partition="auto"):
        from .system import DistributedSystem
        self.comm = comm or world()
        self.problem = problem
        c = self.comm
        mesh = problem.mesh
        if isinstance(partition, str):
            part = partition_elements(mesh, c, partition)
        else:
            part = check_partition(partition, mesh.n_elements, c.size)
        self.part = part
        self.sub = sub = subdomain(mesh, part, c.rank, c.size)
        self.local = collective(c, local_problem, problem, sub, c)
        loc = self.local
        compiled = loc.backend == "numba"
        free = ~loc.constraint_mask().ravel()
        # one rank: the pattern of all dofs, which PETSc's matrix shares (system.SharedCsrMatrix)
        shared = compiled and c.size == 1
        self.asm = PatternAssembler(loc.mesh, np.ones_like(free) if shared else free) if compiled \
            else loc.assembler()
        big = c.size > 1 and max(c.allgather(len(sub.elements))) > STAGGER_ABOVE    # the same on every rank
        release_memory()
        for r in range(c.size if big else 1):    # big: one rank at a time (the set-up's peak memory)
            if not big or r == c.rank:
                loc.element
                release_memory()
                structure = self.asm.pattern() if compiled else self.asm
                release_memory()
            if big:
                c.Barrier()
        if self.local.backend == "numba":
            threads = _threads_per_rank(c.size)
            if hasattr(self.local.element, "compiled"):
                from ..kernels.element import SERIAL_BELOW
                try:                        # the drivers without a block workspace (4.6 kB per element):
                    lean = "serial" if threads == 1 or len(sub.elements) < SERIAL_BELOW else "colour"
                    self.local.element.compiled(structure, mode=lean)
                except TypeError:           # an element whose compiled() takes no mode
                    pass
        self.free = free.reshape(-1, 6)
        self.system = DistributedSystem(c, sub, self.free, structure.indptr, structure.indices, linear,
                                        petsc_options, shared=shared)
        release_memory()
        self.ell = problem.length_scale
        self.n_own = sub.n_owned
        self.mixed = self.local.element.mixed
        self._check_element(problem, c)

    def _check_element(self, problem, c):
        """The whole mesh's coarse-mesh warning (``Problem.check_element``, which needs the whole
        mesh's free edges): the ranks' element indices gathered on rank 0, which warns; and the
        windings of d1 round the nodes (``fem.frame_turns``), which need every element round a
        node: the ranks' windings summed on rank 0, which warns with the whole mesh's node ids."""
        el = self.local.element
        self._check_windings(problem, c, el)
        index = getattr(el, "coarse_curvature", None)
        if index is None:
            return
        parts = c.gather((self.sub.elements, index, np.sqrt(el.area)), root=0)
        if c.rank == 0:
            idx, size = np.zeros(problem.mesh.n_elements), np.ones(problem.mesh.n_elements)
            for ids, i, s in parts:
                idx[ids], size[ids] = i, s
            problem.check_element(idx, size, stacklevel=5)

    def _check_windings(self, problem, c, el):
        """ElementWarning on rank 0 for the whole mesh's nodes round which d1 winds (``_check_element``)."""
        from ..fem.frame_turns import check_node_windings, node_windings, whole_node_windings
        matching = getattr(el, "matching", None)
        local = np.zeros(self.sub.mesh.n_nodes, int) if matching is None else node_windings(self.sub.mesh, matching)
        parts = c.gather((self.sub.nodes, local), root=0)
        if c.rank == 0:
            check_node_windings(None, None, stacklevel=6, windings=whole_node_windings(problem.mesh.n_nodes, parts))

    def relocalize(self):
        """Localise the whole problem's loads again: after a change of their values in place (a
        design's variables), the local parts, which hold copies of the per-node arrays, follow."""
        self.local.loads[:] = [part for ld in self.problem.loads
                               for part in localize_load(ld, self.sub, self.comm)]

    def owned_rows(self, whole):
        """This rank's owned rows (n_own, 6) of a whole-mesh nodal array (n, 6)."""
        return np.ascontiguousarray(np.asarray(whole, float).reshape(-1, 6)[self.sub.nodes[:self.n_own]])

    # ------------------------------------------------------------------ arrays ----------
    def local_frames(self, g):
        """This rank's frames (n_loc, 4, 4) of the whole-mesh frames g (n, 4, 4)."""
        return np.ascontiguousarray(np.asarray(g, float)[self.sub.nodes])

    def gather(self, own):
        """The whole-mesh array (n, ...) from every rank's owned rows ``own`` (n_own, ...), on
        every rank."""
        own = np.ascontiguousarray(own, dtype=float)
        tail = own.shape[1:]
        k = int(np.prod(tail)) if tail else 1
        sub = self.sub
        if self.comm.size == 1:
            full = np.empty((len(sub.owner),) + tail)
            full[sub.order] = own
            return full
        from mpi4py import MPI
        counts = sub.counts * k
        displs = np.concatenate([[0], np.cumsum(counts)[:-1]])
        buf = np.empty(int(counts.sum()))
        self.comm.Allgatherv(own.ravel(), [buf, counts, displs, MPI.DOUBLE])
        full = np.empty((len(sub.owner),) + tail)
        full[sub.order] = buf.reshape((-1,) + tail)
        return full

    def gather_frames(self, g_loc):
        return self.gather(g_loc[:self.n_own])

    # ------------------------------------------------------------------ equations -------
    def evaluate(self, g_loc, lam, tangent=True, stress=None):
        """The :class:`GlobalEvaluation` at the local frames g_loc; with ``tangent`` the PETSc
        tangent is assembled too (its COO values written by the local evaluation)."""
        sys_ = self.system
        out = sys_.data_view() if tangent else None
        ev = collective(self.comm, self.local.evaluate, g_loc, lam, tangent=tangent, assembler=self.asm, out=out,
                        stress=stress)
        r_int, f_ext = sys_.sum_nodal(ev.r_int, ev.f_ext)
        r = np.where(self.free[:self.n_own], r_int - f_ext, 0.0)
        ell = self.ell
        sq = sys_.sumsq(f_ext, r_int, r, ell=ell)
        fs2, en = sys_.allsum(ev.force_scale ** 2, ev.energy)
        scale = max(np.sqrt(sq[0]), np.sqrt(sq[1]), 1e-300)
        rn = np.sqrt(sq[2]) / scale
        floor = 1e3 * np.finfo(float).eps * np.sqrt(fs2) / scale
        if not np.isfinite(rn):
            raise FloatingPointError("non-finite residual")
        if tangent:
            sys_.assemble(ev.K.data)
        return GlobalEvaluation(r_int, f_ext, r, rn, floor, float(np.sqrt(fs2)), float(en), ev)

    def stress(self, g_loc, lam):
        """This rank's element stresses at g_loc (the mixed iteration's start)."""
        return collective(self.comm, self.local.evaluate, g_loc, lam, tangent=False, assembler=self.asm).stress

    def solve(self, gev, g_loc, probe=False):
        """eta (n_loc, 6): K eta = -r, ghosts included."""
        return collective(self.comm, self.system.solve, -gev.r, g_loc=g_loc, ell=self.ell, probe=probe)

    def retract(self, g_loc, eta):
        """g exp(eta) on the owned nodes, then the ghosts from their owners."""
        g_new = np.empty_like(g_loc)
        g_new[:self.n_own] = self.local.retract(g_loc[:self.n_own], eta[:self.n_own])
        return self.system.update_ghost_frames(g_new)

    def linear_stress(self, gev, eta):
        return self.local.linear_stress(gev.local, eta)

    def increment_sq(self, eta):
        """Global |eta|_s^2 (rotations x ell) of the owned rows."""
        e = eta[:self.n_own]
        loc = float(np.sum(e[:, :3] ** 2) + np.sum((e[:, 3:] * self.ell) ** 2))
        return float(self.system.allsum(loc)[0])

    def residual_sq(self, r):
        return float(self.system.sumsq(r, ell=self.ell)[0])

    def dot(self, a, b):
        """Global sum of a . b over owned rows (n_own, 6) (b may be a local (n_loc, 6) array)."""
        return float(self.system.allsum(float(np.sum(a[:self.n_own] * b[:self.n_own])))[0])

    def negative_count(self, g, lam):
        """The number of negative eigenvalues of sym K at the whole-mesh state (g, lam) (the
        tangent assembled on the ranks and its inertia counted there: ``DistributedSystem.
        negative_count``), or None (loads not conservative by their kinds, or K not symmetric:
        ``solvers.stability.negative_count``); the end check's count."""
        if conservative_loads(self.problem.loads) is False:
            return None
        self.evaluate(self.local_frames(g), lam, tangent=True)
        return collective(self.comm, self.system.negative_count)

    def memory(self):
        """Peak resident memory of this rank [bytes] (``ru_maxrss``) and of all ranks."""
        import resource
        mine = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0
        return mine, self.comm.allgather(mine)

    def close(self):
        self.system.destroy()
