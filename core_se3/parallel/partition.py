"""Element partitions of a mesh across ranks, and the node ownership that follows from one.

Two partitioners:

* ``ptscotch`` (the default under MPI when petsc4py imports): PETSc's MatPartitioning with
  PT-Scotch on the dual graph of the elements (two elements adjacent when they share an edge),
  balanced element counts and a short interface;
* ``rcb``: recursive coordinate bisection of the element centroids (NumPy, deterministic):
  each cut halves the longest extent of a group at the element count that keeps the parts in
  proportion (any number of parts).

PT-Scotch's answer may differ from one launch to the next (its random seed), so a run stores
its partition in the checkpoint and a resumed run uses it again (the same bits).

A node belongs to the lowest rank among those whose elements use it; the owners' nodes are
numbered rank after rank (the global numbering of the distributed vectors).
"""
from __future__ import annotations

import numpy as np

from ..errors import ParallelError
from .comm import petsc_comm

__all__ = ["PARTITIONERS", "rcb", "dual_graph", "partition_elements", "node_owners", "check_partition"]

PARTITIONERS = ("auto", "ptscotch", "parmetis", "rcb")


def rcb(points, nparts):
    """Recursive coordinate bisection: part (k,) in [0, nparts) of the points (k, 3).

    Parameters
    ----------
    points : (k, 3) array_like
        E.g. element centroids [length].
    nparts : int
        Number of parts (>= 1).

    Returns
    -------
    (k,) ndarray of int64
        Part sizes differ by at most one from k * share (shares by the part counts of each cut).

    Example
    -------
    >>> import numpy as np
    >>> x = np.c_[np.arange(8.0), np.zeros(8), np.zeros(8)]
    >>> rcb(x, 2).tolist(), np.bincount(rcb(x, 3)).tolist()
    ([0, 0, 0, 0, 1, 1, 1, 1], [3, 2, 3])
    """
    pts = np.asarray(points, float)
    part = np.zeros(len(pts), np.int64)
    todo = [(np.arange(len(pts)), 0, int(nparts))]
    while todo:                                     # a loop over the cuts (nparts - 1 of them)
        ids, first, n = todo.pop()
        if n == 1 or len(ids) == 0:
            part[ids] = first
            continue
        x = pts[ids]
        axis = int(np.argmax(x.max(0) - x.min(0))) if len(ids) else 0
        order = ids[np.lexsort((ids, x[:, axis]))]  # ties broken by id: deterministic
        n_lo = n // 2
        cut = int(round(len(ids) * n_lo / n))
        todo.append((order[:cut], first, n_lo))
        todo.append((order[cut:], first + n_lo, n - n_lo))
    return part


def dual_graph(mesh):
    """The element adjacency through shared edges as CSR (indptr (m+1,), indices).

    Example
    -------
    >>> from core_se3 import mesh
    >>> ptr, idx = dual_graph(mesh.rectangle(3.0, 1.0, 3, 1))
    >>> [idx[ptr[e]:ptr[e + 1]].tolist() for e in range(3)]
    [[1], [0, 2], [1]]
    """
    ee = mesh.elem_edges.ravel()
    el = np.repeat(np.arange(mesh.n_elements), 4)
    order = np.argsort(ee, kind="stable")
    ee, el = ee[order], el[order]
    pair = np.nonzero(ee[1:] == ee[:-1])[0]          # an interior edge: its two elements
    a, b = el[pair], el[pair + 1]
    rows = np.concatenate([a, b])
    cols = np.concatenate([b, a])
    srt = np.lexsort((cols, rows))
    rows, cols = rows[srt], cols[srt]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=mesh.n_elements))])
    return indptr.astype(np.int64), cols.astype(np.int64)


def _petsc_partition(mesh, comm, kind):
    """PETSc MatPartitioning (``kind``) of the dual graph; the (m,) parts on every rank."""
    from petsc4py import PETSc
    if kind not in [getattr(PETSc.MatPartitioning.Type, t) for t in dir(PETSc.MatPartitioning.Type)
                    if t.startswith("PARTITIONING")]:
        raise ParallelError(f"PETSc has no partitioner {kind!r}")
    m, P, r = mesh.n_elements, comm.size, comm.rank
    lo, hi = m * r // P, m * (r + 1) // P
    ptr, idx = dual_graph(mesh)
    lptr = (ptr[lo:hi + 1] - ptr[lo]).astype(PETSc.IntType)
    lidx = idx[ptr[lo]:ptr[hi]].astype(PETSc.IntType)
    pcomm = petsc_comm(comm)
    A = PETSc.Mat().createAIJ(size=((hi - lo, m), (hi - lo, m)), csr=(lptr, lidx, np.ones(len(lidx))), comm=pcomm)
    part = PETSc.MatPartitioning().create(pcomm)
    iset = PETSc.IS()
    try:
        part.setAdjacency(A)
        part.setType(kind)
        part.apply(iset)
        mine = np.array(iset.getIndices(), np.int64)
    except PETSc.Error as exc:
        missing = " (this PETSc was built without it)" if getattr(exc, "ierr", None) == 86 else ""
        raise ParallelError(f"PETSc partitioner {kind!r} failed{missing}: choose another partition (a scenario's "
                            f"[solver] partition; 'auto', 'ptscotch' or 'rcb') -- PETSc said: {exc}") from None
    finally:
        part.destroy()
        A.destroy()
    return np.concatenate(comm.allgather(mine))


def partition_elements(mesh, comm, method="auto"):
    """The rank (m,) of every element, the same array on every rank of ``comm``.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh.
    comm : mpi4py.MPI.Comm or SerialComm
        The ranks.
    method : str, optional
        'auto' (PT-Scotch when several ranks and petsc4py, else 'rcb'), 'ptscotch', 'parmetis'
        (where PETSc has it) or 'rcb' (module docstring).

    Returns
    -------
    (m,) ndarray of int64
        ParallelError for an unknown method or a partition that leaves a rank without elements.

    Example
    -------
    >>> from core_se3 import mesh
    >>> from core_se3.parallel.comm import SerialComm
    >>> partition_elements(mesh.rectangle(2.0, 1.0, 2, 1), SerialComm()).tolist()
    [0, 0]
    """
    if method not in PARTITIONERS:
        raise ParallelError(f"unknown partitioner {method!r}; choose one of {', '.join(PARTITIONERS)}")
    P = comm.size
    if P == 1:
        return np.zeros(mesh.n_elements, np.int64)
    if mesh.n_elements < P:
        raise ParallelError(f"{mesh.n_elements} elements cannot be shared among {P} ranks")
    if method == "auto":
        import importlib.util
        method = "ptscotch" if importlib.util.find_spec("petsc4py") is not None else "rcb"
    if method == "rcb":
        part = rcb(mesh.X[mesh.quads].mean(1), P)
    else:
        part = _petsc_partition(mesh, comm, method)
    return check_partition(part, mesh.n_elements, P)


def check_partition(part, n_elements, nparts):
    """``part`` as int64 after checking it: one rank in [0, nparts) per element, every rank used.

    Example
    -------
    >>> check_partition([0, 1, 1], 3, 2).tolist()
    [0, 1, 1]
    >>> check_partition([0, 0, 0], 3, 2)
    Traceback (most recent call last):
    ...
    core_se3.errors.ParallelError: the partition leaves ranks [1] without elements
    """
    part = np.asarray(part).astype(np.int64).ravel()
    if part.shape != (n_elements,) or part.min() < 0 or part.max() >= nparts:
        raise ParallelError(f"a partition needs one rank in [0, {nparts}) per element ({n_elements})")
    empty = np.nonzero(np.bincount(part, minlength=nparts) == 0)[0]
    if len(empty):
        raise ParallelError(f"the partition leaves ranks {empty.tolist()} without elements")
    return part


def node_owners(quads, part, n_nodes, nparts):
    """(n,) owning rank of every node: the lowest rank among those of its elements (a node in
    no element goes to rank 0).

    Example
    -------
    >>> import numpy as np
    >>> node_owners(np.array([[0, 1, 4, 3], [1, 2, 5, 4]]), np.array([1, 0]), 6, 2).tolist()
    [1, 0, 0, 1, 0, 0]
    """
    owner = np.zeros(n_nodes, np.int64)
    used = np.zeros(n_nodes, bool)
    for p in range(nparts - 1, -1, -1):              # a loop over ranks: the lowest one wins
        nodes = quads[part == p].ravel()
        owner[nodes] = p
        used[nodes] = True
    owner[~used] = 0
    return owner
