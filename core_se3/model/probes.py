"""Probes: points of the mesh whose position and frame are recorded at every step."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import lie
from ..errors import OptionError
from ..mesh.core import chain_order

__all__ = ["Probe", "along_line"]


def along_line(mesh, nodes, name="probe"):
    """The node set ordered along the line of element edges it forms (as given if consecutive
    nodes are joined already); an OptionError naming the probe if three or more nodes form no
    line (a patch, scattered points: no midpoint to record).  Before, a predicate's nodes were
    taken in id order: on a refined or Gmsh mesh the "midpoint" of an edge was a corner.

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.refine(mesh.rectangle(4.0, 1.0, 4, 2))
    >>> along_line(m, [4, 9, 14, 23, 32]).tolist()            # id order is not the line's
    [4, 23, 9, 32, 14]
    """
    nodes = np.asarray(nodes, np.int64)
    if len(nodes) < 3:
        return nodes
    inset = np.zeros(mesh.n_nodes, bool)
    inset[nodes] = True
    segs = mesh.edge_nodes[inset[mesh.edge_nodes].all(1)]
    order = chain_order([tuple(e) for e in segs.tolist()]) if len(segs) else np.array([], np.int64)
    chained = sorted(order.tolist()) == sorted(nodes.tolist())
    if len(segs) == len(nodes) and chained:
        _closed_loop(name, len(nodes))
    key = {tuple(e) for e in np.sort(mesh.edge_nodes, 1).tolist()}
    if all(tuple(sorted(p)) in key for p in zip(nodes[:-1].tolist(), nodes[1:].tolist())):
        return nodes
    if len(segs) == len(nodes) - 1 and chained:
        return order
    raise OptionError(f"probe {name!r}: its {len(nodes)} nodes are not a line of element edges, so they have no "
                      "midpoint to record; select a line (an edge's nodes), one node, or two nodes")


def _closed_loop(name, k):
    """OptionError for a probe on a closed loop of element edges: a loop has no midpoint, and the
    probe sat wherever the listed order put it (a tube's end ring of 8 nodes: (0.38, 2, -0.92) or
    (0.38, 2, 0.92) for the same nodes listed from another start)."""
    raise OptionError(f"probe {name!r}: its {k} nodes form a closed loop of element edges (a hole's or a tube's "
                      "rim), which has no midpoint to record; select one node of it (nodes = [ID]), two nodes, or "
                      "an open part of the loop")


def _turn(g, angle):
    """g Rz(angle): the frame g turned about its own normal d3 by ``angle`` [rad]."""
    if angle == 0.0:
        return g
    c, s = np.cos(angle), np.sin(angle)
    return g @ np.array([[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


@dataclass
class Probe:
    """A point of the mesh between two nodes a, b: the frame g_a exp((1 - wa) log(g_a^-1 g_b))
    on the SE(3) geodesic (wa = 1: the node a itself), of the nodes' frames turned about their
    normals by ``turns`` (the mesh's least-turn gauge, ``Mesh.gauge_angles``, on which the
    default element builds its edges).  Without the turns the geodesic between frames whose d1
    the user chose differently (a turn about the normal: a choice of the user, not of the shell)
    is a screw that bows out of the edge: on a flat 10 x 1 strip (8 x 1 elements) whose tip
    nodes' d1 differ by 1 rad (pi/2) the tip probe read a deflection 1.9 % (3.1 %) below its
    nodes' own, converged and without a word.  The frame at the point is turned back by the mean
    turn (:meth:`unturn`), so that where the two turns are equal the probe is exactly the
    geodesic of the user's frames (frame included).

    Parameters
    ----------
    name : str
        The probe's name (a key of ``StepResult.probes``).
    node_a, node_b : int
        The two nodes.
    wa : float, optional
        The weight of node a (1: a itself, 0.5: halfway along the geodesic).
    turns : (float, float), optional
        The turns [rad] of the frames of a and b about their normals before they are joined
        (unused by a probe of one node: it reports that node's frame as given).

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(2.0, 1.0, 1, 1)
    >>> p = Probe.edge_midpoint("tip", m.node_set("x1"))
    >>> p.state(m.g0)[0].tolist()
    [2.0, 0.0, 0.0]
    """
    name: str
    node_a: int
    node_b: int
    wa: float = 1.0
    turns: tuple = (0.0, 0.0)

    def ends(self, ga, gb):
        """The frames of a and b (stacks ``(..., 4, 4)`` too) turned by ``turns``: the two ends
        of the probe's geodesic."""
        return _turn(ga, float(self.turns[0])), _turn(gb, float(self.turns[1]))

    def unturn(self, gm):
        """The frame ``gm`` on the geodesic of :meth:`ends` turned back by the weighted mean of
        ``turns``: the probe's frame as the user's frames give it where the turns are equal
        (exactly the geodesic of the user's frames there; only the position depends on them)."""
        return _turn(gm, -(self.wa * float(self.turns[0]) + (1.0 - self.wa) * float(self.turns[1])))

    def state(self, g, compiled=False):
        """(position (3,), rotation (3, 3)) of the probe at the frames g (``compiled``: with the
        numba kernel ``kernels.lie.geodesic_point``, the same to round-off)."""
        ga, gb = g[self.node_a], g[self.node_b]
        if self.node_a == self.node_b or self.wa == 1.0:
            return ga[:3, 3].copy(), ga[:3, :3].copy()
        ga, gb = self.ends(ga, gb)
        if compiled:
            from ..kernels.lie import geodesic_point
            gm = np.empty((4, 4))
            geodesic_point(np.ascontiguousarray(ga, dtype=float), np.ascontiguousarray(gb, dtype=float),
                           1.0 - self.wa, gm)
        else:
            gm = ga @ lie.exp((1.0 - self.wa) * lie.log(lie.relative(ga, gb)))
        gm = self.unturn(gm)
        return gm[:3, 3].copy(), gm[:3, :3].copy()

    def linear(self, g0, eta):
        """(displacement (3,), rotation vector (3,)) of the probe in a linear analysis: the probe
        map linearised about the reference frames g0 along the nodal increments eta (n, 6)
        (a node: u = R0 v, w = R0 omega, as ``solvers.linear``'s state; between nodes the
        geodesic point's body increment Ad(exp(-t psi)) eta_a + t dexp(t psi) dpsi, with
        dpsi = dexp(psi)^-1 (eta_b - Ad(exp(-psi)) eta_a) the linearised log(g_a^-1 g_b)).
        The probe of the linear state itself is not linear in the load: halfway along the tip
        edge of a cylinder panel it read u/s 0.053, 0.217, -0.169 at the loads s = 1, 2, 4.

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import mesh
        >>> m = mesh.rectangle(2.0, 1.0, 1, 1)
        >>> eta = np.zeros((4, 6)); eta[m.node_set("x1"), 2] = (0.1, 0.3)   # lifts 0.1 and 0.3
        >>> [x.round(12).tolist() for x in Probe.edge_midpoint("tip", m.node_set("x1")).linear(m.g0, eta)]
        [[0.0, 0.0, 0.2], [0.0, 0.0, 0.0]]
        """
        a, b = self.node_a, self.node_b
        if a == b or self.wa == 1.0:
            em, g0m = np.asarray(eta[a], float), g0[a]
        else:
            t = 1.0 - self.wa
            ga, gb = self.ends(g0[a], g0[b])
            ea, eb = self.body_increments(eta[a], eta[b])
            psi = lie.log(lie.relative(ga, gb))
            dpsi = lie.dexp_inv(psi) @ (eb - lie.Ad(lie.exp(-psi)) @ ea)
            em = lie.Ad(lie.exp(-t * psi)) @ ea + t * lie.dexp(t * psi) @ dpsi
            g0m = ga @ lie.exp(t * psi)           # (R0 em: lab vectors, whichever turn of g0m)
        R0 = g0m[:3, :3]
        return R0 @ em[:3], R0 @ em[3:]

    def body_increments(self, eta_a, eta_b):
        """The body-frame twists (6,) of nodes a and b restated in their turned frames
        (``ends``): a twist's two halves turned back by each node's turn."""
        out = []
        for e, angle in zip((eta_a, eta_b), self.turns):
            e = np.asarray(e, float)
            if angle != 0.0:
                Rt = _turn(np.eye(4), float(angle))[:3, :3].T
                e = np.r_[Rt @ e[:3], Rt @ e[3:]]
            out.append(e)
        return out

    @classmethod
    def edge_midpoint(cls, name, nodes, angles=None, g0=None):
        """The middle of an ordered node set: its middle node, or halfway between the two
        (``angles``: (n,) turns of every node of the mesh, ``Mesh.gauge_angles``; default none).
        With ``g0`` (n, 4, 4), the reference frames, b's turn also takes the quarter turn that
        leaves the two frames least turned about the normal (``mesh.gauge.edge_matching``, as the
        default element joins them across a cross field's cuts): between a mesh file's default
        frames on a doubly curved shell, whose d1 jump by quarter turns, the geodesic was a screw
        of 90 or 180 deg (a probe between nodes whose d1 differ by 180 deg on the quarter
        hemisphere read a point 1.3 (the element's size: 2.6) off the edge, its frame 180 deg off).

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import mesh
        >>> from core_se3.mesh.gauge import turned_about_normal
        >>> m = mesh.rectangle(2.0, 1.0, 1, 1)
        >>> g = turned_about_normal(m.g0, np.array([0.0, 0.0, np.pi, 0.0]))      # node 2's d1 reversed
        >>> Probe.edge_midpoint("tip", [2, 3], g0=g).state(g)[0].round(12).tolist()    # the edge's middle
        [1.0, 0.5, 0.0]
        >>> Probe.edge_midpoint("tip", [2, 3]).state(g)[0].round(12).tolist()          # a half-turn screw's
        [1.0, 1.5, 0.0]
        """
        nodes = list(nodes)
        k = len(nodes)
        if k % 2 == 1:
            return cls(name, nodes[k // 2], nodes[k // 2], 1.0)
        a, b = nodes[k // 2 - 1], nodes[k // 2]
        turns = (0.0, 0.0) if angles is None else (float(angles[a]), float(angles[b]))
        if g0 is not None:
            from ..mesh.gauge import edge_matching
            q = edge_matching(np.stack([_turn(g0[a], turns[0]), _turn(g0[b], turns[1])]), np.array([[0, 1]]))
            turns = turns if q is None else (turns[0], turns[1] + 0.5 * np.pi * float(q[0]))
        return cls(name, a, b, 0.5, turns)
