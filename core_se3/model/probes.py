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
    key = {tuple(e) for e in np.sort(mesh.edge_nodes, 1).tolist()}
    if all(tuple(sorted(p)) in key for p in zip(nodes[:-1].tolist(), nodes[1:].tolist())):
        return nodes
    inset = np.zeros(mesh.n_nodes, bool)
    inset[nodes] = True
    segs = mesh.edge_nodes[inset[mesh.edge_nodes].all(1)]
    order = chain_order([tuple(e) for e in segs.tolist()]) if len(segs) else np.array([], np.int64)
    if len(segs) in (len(nodes) - 1, len(nodes)) and sorted(order.tolist()) == sorted(nodes.tolist()):
        return order
    raise OptionError(f"probe {name!r}: its {len(nodes)} nodes are not a line of element edges, so they have no "
                      "midpoint to record; select a line (an edge's nodes), one node, or two nodes")


@dataclass
class Probe:
    """A point of the mesh between two nodes a, b: the frame g_a exp((1 - wa) log(g_a^-1 g_b))
    on the SE(3) geodesic (wa = 1: the node a itself).

    Parameters
    ----------
    name : str
        The probe's name (a key of ``StepResult.probes``).
    node_a, node_b : int
        The two nodes.
    wa : float, optional
        The weight of node a (1: a itself, 0.5: halfway along the geodesic).

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

    def state(self, g, compiled=False):
        """(position (3,), rotation (3, 3)) of the probe at the frames g (``compiled``: with the
        numba kernel ``kernels.lie.geodesic_point``, the same to round-off)."""
        ga, gb = g[self.node_a], g[self.node_b]
        if self.node_a == self.node_b or self.wa == 1.0:
            return ga[:3, 3].copy(), ga[:3, :3].copy()
        if compiled:
            from ..kernels.lie import geodesic_point
            gm = np.empty((4, 4))
            geodesic_point(np.ascontiguousarray(ga, dtype=float), np.ascontiguousarray(gb, dtype=float),
                           1.0 - self.wa, gm)
            return gm[:3, 3].copy(), gm[:3, :3].copy()
        rel = lie.log(lie.relative(ga, gb))
        gm = ga @ lie.exp((1.0 - self.wa) * rel)
        return gm[:3, 3].copy(), gm[:3, :3].copy()

    @classmethod
    def edge_midpoint(cls, name, nodes):
        """The middle of an ordered node set: its middle node, or halfway between the two."""
        nodes = list(nodes)
        k = len(nodes)
        if k % 2 == 1:
            return cls(name, nodes[k // 2], nodes[k // 2], 1.0)
        return cls(name, nodes[k // 2 - 1], nodes[k // 2], 0.5)
