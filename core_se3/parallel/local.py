"""One rank's share of a Problem: its elements, their nodes (owned first, then ghosts), and the
local Problem on the sub-mesh of those elements that the unchanged element kernels evaluate.

The global node ids of the local nodes are ``Subdomain.nodes``: the ``n_owned`` nodes this rank
owns (ascending), then the ghosts (nodes of its elements owned by other ranks, ascending in the
global numbering of the distributed vectors).  Nodal loads and penalty supports are kept on
owned nodes only (each counts once), element loads on the rank's elements; supports hold the
same dofs on every local node, ghosts included.
"""
from __future__ import annotations

import numpy as np

from ..assembly import Assembler
from ..errors import ParallelError
from ..fem import ELEMENTS, RegionMaterial
from ..mesh import Mesh
from ..model import Problem
from .localize import localize_load, localize_support
from .partition import node_owners

__all__ = ["Subdomain", "subdomain", "local_problem", "PatternAssembler"]


class Subdomain:
    """The index maps of one rank (see the module docstring).

    Attributes
    ----------
    rank, size : int
        This rank and the number of ranks.
    part : (m,) ndarray
        The rank of every element; ``elements`` (m_loc,): this rank's, ascending.
    owner : (n,) ndarray
        The rank of every node; ``order`` (n,): the global nodes in the numbering of the
        distributed vectors (rank after rank), ``index`` (n,): its inverse.
    nodes : (n_loc,) ndarray
        Global ids of the local nodes, owned first; ``n_owned`` of them are owned.
    g2l : (n,) ndarray
        Local id of every global node (-1: not on this rank).
    start : int
        Index of this rank's first owned node in the distributed numbering.
    counts : (size,) ndarray
        Owned nodes per rank.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(2.0, 1.0, 2, 1)                  # nodes 0 1 2 / 3 4 5
    >>> s = subdomain(m, np.array([0, 1]), rank=1, size=2)
    >>> s.elements.tolist(), s.nodes.tolist(), s.n_owned, s.start
    ([1], [2, 5, 1, 4], 2, 4)
    """

    def __init__(self, part, owner, rank, size, quads):
        self.rank, self.size = int(rank), int(size)
        self.part, self.owner = part, owner
        n = len(owner)
        self.order = np.argsort(owner, kind="stable")
        self.index = np.empty(n, np.int64)
        self.index[self.order] = np.arange(n)
        self.counts = np.bincount(owner, minlength=size)
        self.start = int(self.counts[:rank].sum())
        self.elements = np.nonzero(part == rank)[0]
        used = np.unique(quads[self.elements])
        owned = self.order[self.start:self.start + self.counts[rank]]
        ghosts = used[owner[used] != rank]
        ghosts = ghosts[np.argsort(self.index[ghosts], kind="stable")]
        self.nodes = np.concatenate([owned, ghosts]).astype(np.int64)
        self.n_owned = len(owned)
        self.g2l = -np.ones(n, np.int64)
        self.g2l[self.nodes] = np.arange(len(self.nodes))
        self.e2l = -np.ones(len(part), np.int64)
        self.e2l[self.elements] = np.arange(len(self.elements))
        self.mesh = None

    @property
    def ghost_index(self):
        """Distributed indices of the ghost nodes (ascending)."""
        return self.index[self.nodes[self.n_owned:]]

    def owned_local(self, global_nodes):
        """(positions into ``global_nodes``, their local ids) of the ones this rank owns."""
        loc = self.g2l[np.asarray(global_nodes, np.int64)]
        pos = np.nonzero((loc >= 0) & (loc < self.n_owned))[0]
        return pos, loc[pos]

    def local_nodes(self, global_nodes):
        """(positions into ``global_nodes``, their local ids) of the ones on this rank."""
        loc = self.g2l[np.asarray(global_nodes, np.int64)]
        pos = np.nonzero(loc >= 0)[0]
        return pos, loc[pos]


def subdomain(mesh, part, rank, size):
    """The :class:`Subdomain` of ``rank`` for the element partition ``part``; its ``mesh`` is the
    sub-mesh of the rank's elements on its local nodes.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The whole mesh.
    part : (m,) array of int
        The rank of every element.
    rank, size : int
        This rank and the number of ranks.

    Returns
    -------
    Subdomain

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> s = subdomain(mesh.rectangle(2.0, 1.0, 2, 1), np.array([0, 1]), rank=0, size=2)
    >>> s.mesh.n_elements, s.mesh.n_nodes, s.n_owned, s.ghost_index.tolist()
    (1, 4, 4, [])
    """
    owner = node_owners(mesh.quads, part, mesh.n_nodes, size)
    sub = Subdomain(part, owner, rank, size, mesh.quads)
    # nodes that no element uses belong to rank 0 (and stay out of the sub-mesh's quads)
    sub.mesh = Mesh(mesh.g0[sub.nodes], sub.g2l[mesh.quads[sub.elements]])
    sub.mesh.gauge_angles = mesh.gauge_angles[sub.nodes]      # the serial element's frames
    # the whole mesh's ids of its elements and nodes: the element's checks name them, and leave the
    # windings of d1 round a node, which need every element round it, to the run
    # (``fem.frame_turns.whole_node_windings``)
    sub.mesh.whole_ids = (sub.elements, sub.nodes)
    return sub


def _local_material(material, elements):
    if isinstance(material, RegionMaterial):
        return RegionMaterial(material.materials, material.index[elements])
    return material


def local_problem(problem, sub, comm=None):
    """The Problem of ``sub``'s elements and nodes: the same element kind and material (per
    element), supports on its nodes, loads localised (``localize``), the global length scale.

    Parameters
    ----------
    problem : core_se3.Problem
        The whole problem (the same on every rank).
    sub : Subdomain
        This rank's share.
    comm : mpi4py.MPI.Comm, optional
        The ranks, for the loads whose solver hooks are collective (contact).

    Returns
    -------
    core_se3.Problem
        Its element is built at first use; ParallelError for a load without a distributed form.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> s = subdomain(p.mesh, np.array([0, 1]), rank=1, size=2)
    >>> q = local_problem(p, s)
    >>> q.mesh.n_nodes, len(q.supports), [ld.nodes.tolist() for ld in q.loads], q.length_scale == p.length_scale
    (4, 0, [[0, 1]], True)
    """
    if ELEMENTS.lookup(problem.element_name).stateful:
        raise ParallelError(f"the distributed solver needs a path-independent element; "
                            f"{problem.element_name!r} carries its strain as a state (run it serially)")
    loc = Problem(sub.mesh, _local_material(problem.material, sub.elements), element=problem.element_name,
                  linear_solver=problem.linear_solver, backend=problem.backend)
    loc.length_scale = problem.length_scale
    for s in problem.supports:
        ls = localize_support(s, sub)
        if ls is not None:
            loc.supports.append(ls)
    for ld in problem.loads:
        for part in localize_load(ld, sub, comm):
            loc.loads.append(part)
    return loc


class PatternAssembler(Assembler):
    """An Assembler of the compiled backend only: the free dofs and the fixed CSR pattern
    (``Assembler.pattern()``), without the NumPy reference's block-slot arrays (about 11 kB per
    element, more than the element itself); ``matrix`` builds the full Assembler at its first
    use (a problem evaluated by NumPy).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> a = PatternAssembler(m, np.ones(6 * m.n_nodes, bool))
    >>> a.nfree, a.vector(np.arange(36.0).reshape(6, 6))[:3].tolist()
    (36, [0.0, 1.0, 2.0])
    """

    def __init__(self, mesh, free):                    # noqa: D107 (no call of the base __init__)
        self.mesh = mesh
        self._pattern = None
        self.ndof = 6 * mesh.n_nodes
        self.free = np.asarray(free, bool)
        self.nfree = int(self.free.sum())
        self._full = None

    def matrix(self, element_blocks=None, edge_blocks=None, node_blocks=None):
        if self._full is None:
            self._full = Assembler(self.mesh, self.free)
        return self._full.matrix(element_blocks, edge_blocks, node_blocks)
