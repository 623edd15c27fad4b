"""Loads and supports restricted to one rank's share (``local.Subdomain``), renumbered to its
local nodes and elements.

A nodal load (nodal and edge forces and moments, magnetic dipoles, penalty springs) keeps the
nodes this rank owns, so that each acts once when the ranks' forces are summed; a surface load
(pressure, body force, gravity) keeps this rank's elements, whose nodal parts the sum adds up
as the serial assembly does.  The magnetisation's nodal dipoles are those of the whole mesh
(computed once from all magnetised elements), so a node on a rank boundary gets its whole
dipole.  Contact keeps the contact nodes this rank owns (maybe none: every rank takes part in
its collective solver hooks), see :class:`LocalContact`.  A load class of one's own takes part
by a method ``localized(part)`` returning the list of local loads, ``part`` being this
module's :class:`LocalView` of the subdomain.
"""
from __future__ import annotations

import copy

import numpy as np

from ..errors import ParallelError
from ..model import MagneticLoad, NodalLoad, SurfaceLoad
from ..model.contact import ContactLoad
from ..model.supports import LabSpring, LabTiltSpring, Prescribed, RotationComponentSpring
from .comm import SerialComm

__all__ = ["LocalView", "LocalContact", "localize_load", "localize_support"]


class LocalView:
    """What a ``Load.localized(part)`` method gets: the local mesh and the index maps.

    Attributes
    ----------
    mesh : core_se3.mesh.Mesh
        The sub-mesh (local node and element ids).
    owned_local(global_nodes) -> (positions, local ids)
        The given nodes this rank owns (count a nodal quantity once).
    local_nodes(global_nodes) -> (positions, local ids)
        The given nodes on this rank (owned or ghost).
    local_elements(global_elements) -> (positions, local ids)
        The given elements of this rank.
    comm : mpi4py.MPI.Comm or SerialComm
        The ranks (for a load whose solver hooks must agree on every rank).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.parallel.local import subdomain
    >>> v = LocalView(subdomain(mesh.rectangle(2.0, 1.0, 2, 1), np.array([0, 1]), rank=1, size=2))
    >>> [a.tolist() for a in v.owned_local([1, 2, 5])], [a.tolist() for a in v.local_elements([0, 1])]
    ([[1, 2], [0, 1]], [[1], [0]])
    """

    def __init__(self, sub, comm=None):
        self.sub = sub
        self.mesh = sub.mesh
        self.comm = comm if comm is not None else SerialComm()

    def owned_local(self, global_nodes):
        return self.sub.owned_local(global_nodes)

    def local_nodes(self, global_nodes):
        return self.sub.local_nodes(global_nodes)

    def local_elements(self, global_elements):
        loc = self.sub.e2l[np.asarray(global_elements, np.int64)]
        pos = np.nonzero(loc >= 0)[0]
        return pos, loc[pos]


def _nodal(ld, view):
    pos, loc = view.owned_local(ld.nodes)
    if not len(pos):
        return []
    return [NodalLoad(view.mesh.n_nodes, loc, ld.weights[pos], ld.force, ld.moment, ld.follower, ld.scale,
                      ld.name)]


def _surface(ld, view):
    pos, loc = view.local_elements(ld.elements)
    if not len(pos):
        return []
    q = ld.p if ld.follower else ld.q
    return [SurfaceLoad(view.mesh, q, ld.follower, loc, ld.scale, ld.name, None if ld.j0 is None else ld.j0[pos])]


def _magnetic(ld, view):
    mag = ld.mag
    pos, loc = view.owned_local(mag.nodes)
    if not len(pos):
        return []
    part = copy.copy(mag)
    part.mesh = view.mesh
    part.nodes, part.mu, part.area = loc, mag.mu[pos], mag.area[pos]
    node_area = np.zeros(view.mesh.n_nodes)
    lp, ll = view.local_nodes(np.arange(len(mag.node_area)))
    node_area[ll] = mag.node_area[lp]
    part.node_area = node_area
    part.elements = view.local_elements(mag.elements)[1]
    out = MagneticLoad(part, ld.field, ld.name)
    return [out]


def _spring(ld, view, arrays):
    pos, loc = view.owned_local(ld.nodes)
    if not len(pos):
        return []
    part = copy.copy(ld)
    part.n, part.nodes, part.whole_nodes = view.mesh.n_nodes, loc, np.asarray(ld.node_ids)[pos]
    for name in arrays:
        setattr(part, name, np.ascontiguousarray(getattr(ld, name)[pos]))
    return [part]


class LocalContact(ContactLoad):
    """A :class:`~core_se3.model.contact.ContactLoad` on one rank: the contact nodes it owns (each
    node's force counts once in the sum over the ranks; a rank may own none) and the contact faces
    of its elements (their face samples, and the crossing check of their paths), with the solver
    hooks made collective -- the step cap is the smallest of the ranks', a refused start is
    refused on every rank, the gap error of an Uzawa update is the largest, so that every rank
    takes the serial decision.  A face's nodes that another rank owns come along as contact
    nodes of zero area (they carry the face, not a nodal force: their owner applies that).  The
    multipliers are exchanged as whole arrays (``multipliers`` returns, ``set_multipliers``
    takes, all contact nodes' and faces'), and after every update the whole problem's load gets
    them too: the step records and checkpoints are the serial ones.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import make_obstacle
    >>> from core_se3.parallel.local import subdomain
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e4, 0.0, 0.02))
    >>> c = p.add_obstacle(make_obstacle("half_space", point=(0, 0, -0.5), normal=(0, 0, 1)))
    >>> s = subdomain(p.mesh, np.array([0, 1]), rank=1, size=2)
    >>> part = localize_load(c, s)[0]
    >>> part.nodes.tolist(), part.A.round(3).tolist()     # owned nodes, then the face's others (area 0)
    ([0, 1, 2, 3], [0.25, 0.25, 0.0, 0.0])
    >>> part.multipliers().shape                          # all multipliers and penalty factors
    (12,)
    """

    def __init__(self, whole, view):                   # noqa: D107 (the whole load is built already)
        if getattr(whole, "mu", 0.0) > 0:
            from ..errors import ContactError
            raise ContactError(f"obstacle {whole.name!r}: friction is not distributed over ranks yet; run it "
                               "on one process")
        self.__dict__.update(copy.copy(whole).__dict__)
        pos, loc = view.owned_local(whole.nodes)
        qpos = view.local_elements(whole._quad_el)[0]          # the faces of this rank's elements
        extra = np.setdiff1d(np.unique(whole._quads[qpos]), pos)  # their nodes another rank owns
        npos = np.concatenate([pos, extra]).astype(np.int64)
        self.whole, self.pos, self.comm = whole, pos, view.comm
        self.fpos = qpos if len(whole.face_el) else np.zeros(0, np.int64)   # face samples: as the faces
        self.n, self.nodes = view.mesh.n_nodes, np.concatenate([loc, view.local_nodes(whole.nodes[extra])[1]])
        for name in ("A", "side", "c", "k", "_active", "_normals"):
            setattr(self, name, np.array(getattr(whole, name)[npos]))
        self.A[len(pos):] = 0.0                                # a nodal force counts on its owner only
        self._npos = npos
        self.lam0, self.lam, self.soft = (self._samples(getattr(whole, name)) for name in ("lam0", "lam", "soft"))
        where = np.full(len(whole.nodes), -1, np.int64)
        where[npos] = np.arange(len(npos))
        self._quads = where[whole._quads[qpos]]
        self._quad_el = view.local_elements(whole._quad_el[qpos])[1]
        self.face_q = self._quads if len(self.fpos) else np.zeros((0, 4), np.int64)      # as ContactLoad._faces
        self.face_el = self._quad_el if len(self.fpos) else np.zeros(0, np.int64)
        self.Af, self.kf = whole.Af[self.fpos], whole.kf[self.fpos]
        self._ids = whole.nodes[npos], whole._quad_el[qpos]         # the whole mesh's, for messages
        held = whole._held                                          # the supports of the local nodes
        self._held = None if held is None else (lambda: held()[view.sub.nodes])

    @property
    def node_ids(self):
        return self._ids[0]

    @property
    def face_ids(self):
        return self._ids[1]

    def _samples(self, whole_array):
        """This rank's entries (its nodes', then its face samples') of a whole per-sample array."""
        kn = len(self.whole.nodes)
        return np.concatenate([whole_array[self._npos], whole_array[kn + self.fpos]])

    def _publish(self):
        """Every rank's multipliers (of its owned nodes and its faces) and the global gap error
        into the whole load."""
        ko, kl, kn = len(self.pos), len(self.nodes), len(self.whole.nodes)
        mine = (self.pos, self.fpos, self.lam[:ko], self.soft[:ko], self.lam[kl:], self.soft[kl:])
        for pos, fpos, lam, soft, lam_f, soft_f in self.comm.allgather(mine):
            self.whole.lam[pos], self.whole.soft[pos] = lam, soft
            self.whole.lam[kn + fpos], self.whole.soft[kn + fpos] = lam_f, soft_f
        self.whole.gap_error = self.gap_error

    def limit_increment(self, g, eta, lam):
        return float(min(self.comm.allgather(super().limit_increment(g, eta, lam))))

    def step_error(self, g0, lam0, g1, lam1):
        return next((w for w in self.comm.allgather(super().step_error(g0, lam0, g1, lam1)) if w), "")

    def _sum_shared(self, shift, count):
        # a node on a partition boundary is carried by faces of two ranks: their sums, as serially
        kn = len(self.whole.nodes)
        total, number = np.zeros((kn, 3)), np.zeros(kn)
        for npos, s, c in self.comm.allgather((self._npos, shift, count)):
            np.add.at(total, npos, s)
            np.add.at(number, npos, c)
        return total[self._npos], number[self._npos]

    def lift_off(self, g0, lam0, g1, lam1):
        every = self.comm.allgather(super().lift_off(g0, lam0, g1, lam1))
        top = max(v for v, _ in every)
        return top, max(node for v, node in every if v == top)

    def start_error(self, g, lam):
        return next((w for w in self.comm.allgather(super().start_error(g, lam)) if w), "")

    def largest(self, value):
        return max(self.comm.allgather(value))

    def failure_hint(self):
        """The hint of the lowest rank that has one, on every rank (the deepest node pressed, held
        by a support, is on one rank: the others, rank 0 that writes among them, said nothing)."""
        return next((h for h in self.comm.allgather(super().failure_hint()) if h), "")

    def update_multipliers(self, g, lam):
        ratio = super().update_multipliers(g, lam)        # the decision on the largest gap error
        self._publish()
        return ratio

    def multipliers(self):
        return self.whole.multipliers()

    def set_multipliers(self, lam=None):
        self.whole.set_multipliers(lam)
        self.lam, self.soft = self._samples(self.whole.lam), self._samples(self.whole.soft)


_RULES = {
    NodalLoad: _nodal,
    SurfaceLoad: _surface,
    MagneticLoad: _magnetic,
    LabSpring: lambda ld, v: _spring(ld, v, ("D", "P", "X0")),
    LabTiltSpring: lambda ld, v: _spring(ld, v, ("t",)),
    RotationComponentSpring: lambda ld, v: _spring(ld, v, ("R0", "b")),
    ContactLoad: lambda ld, v: [LocalContact(ld, v)],
}


def localize_load(load, sub, comm=None):
    """The local loads (a list, maybe empty) of ``load`` on ``sub`` (module docstring).

    Parameters
    ----------
    load : core_se3.model.Load
        A built-in load, or one with a ``localized(part)`` method.
    sub : core_se3.parallel.local.Subdomain
        This rank's share.
    comm : mpi4py.MPI.Comm, optional
        The ranks (default a one-rank SerialComm).

    Returns
    -------
    list of Load
        ParallelError for a load class without a distributed form.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.model import NodalLoad
    >>> from core_se3.parallel.local import subdomain
    >>> s = subdomain(mesh.rectangle(2.0, 1.0, 2, 1), np.array([0, 1]), rank=0, size=2)
    >>> [ld.nodes.tolist() for ld in localize_load(NodalLoad(6, [1, 2], [0.5, 0.5], (0, 0, 1.0)), s)]
    [[1]]
    """
    own = getattr(load, "localized", None)
    if callable(own):
        return list(own(LocalView(sub, comm)))
    rule = _RULES.get(type(load))          # the exact class: a subclass may change the equations
    if rule is not None:
        return rule(load, LocalView(sub, comm))
    raise ParallelError(f"load {getattr(load, 'name', '?')!r} ({type(load).__name__}) has no distributed form: "
                        "give its class a localized(part) method (docs/PARALLEL.md) or run serially")


def localize_support(support, sub):
    """A Prescribed support on ``sub``'s local nodes (ghosts included), or None if it holds none.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.model.supports import Prescribed
    >>> from core_se3.parallel.local import subdomain
    >>> s = subdomain(mesh.rectangle(2.0, 1.0, 2, 1), np.array([0, 1]), rank=1, size=2)
    >>> localize_support(Prescribed([0, 1, 3], np.ones(6, bool)), s).nodes.tolist()
    [2]
    """
    pos, loc = sub.local_nodes(support.nodes)
    if not len(pos):
        return None
    target = support.target
    if target is not None:
        def target(lam, full=support.target, pos=pos):
            return np.asarray(full(lam))[pos]
    return Prescribed(loc, support.fixed, target)
