"""Frames that turn about the normal within an element: the check of the element's reference
geometry (issue 30, doubly curved shells).

Why.  The default element ties its strains along its edges in the nodal frames it builds on
(``element_default``, "Frames": the user's frames turned by the least-turn gauge, which keeps the
user's frames on doubly curved parts).  Its reference tangents are the translational parts of
the edge twists log(g_a^-1 g_b): an edge whose end frames turn by t about the normal is joined
by a helix whose tangent is turned by about t / 2 from the chord, so the element's area element
j0 = |A_1 x A_2| falls with the turns of its edges against each other.  On a closed sphere read
from a file (no field of d1 without such turns exists on it) the elements across the cross
field's cuts (d1 turning by 90 deg and more) had j0 3 to 25 % of their quads' area, and a
pressurised sphere displaced by -5.7 ... 7.2 times the exact p R^2 (1 - nu) / (2 E h) at
16 x 16 per face -- solved, converged, silent.

The check (at the element's build, :func:`check_frame_turns`).  Measured on the closed cubed
sphere, on Gmsh's unstructured domes and on the generators' meshes: every element whose frames
turn by at most 60 deg about its normal between two of its nodes has j0 within 0.94 ... 1.04 of
its bilinear quad's area (the generators' hemisphere: turns up to 37 deg at 2 x 2, area 1.00 ...
1.03); above 60 deg the area ratio is anything from 0.03 to 1.04.  So:

* an element whose area from its frames is below MIN_AREA_RATIO = 0.5 of its quad's is an
  ElementTooDistortedError (its stiffness is not that of the shell; the sphere's cut elements);
* an element turning by more than MAX_NORMAL_TURN = 60 deg, or with an area ratio below
  WARN_AREA_RATIO = 0.9, is an ElementWarning naming it (Gmsh's domes: 33 and 25 elements of
  turns up to 87 deg, area ratios down to 0.74, whose pinched deflections came out within 5 %
  and 0.7 % of the meridian frames' -- right where measured, not shown right everywhere; with
  the cuts' quarter turns matched, ``element_default``, "Cuts": 3 and 4 elements, area ratios
  down to 0.90 / 0.76).

Round a cross field's singular node an element whose quarter turns do not close compares its
sides in frames turned by their actual angles, in which it turns by 0.1 deg or less: on Gmsh's
finer dome those had area ratios 0.895 ... 1.130 (measured after the bar above; a ratio above 1
is not checked).  Re-measured with the angles carried to the element's mean normal
(``element_default.transported_d1_angles``): 1.013 ... 1.028 on Gmsh's domes, 1.013 ... 1.019 on
the closed cubed sphere (4 ... 16 per face), inside the other elements' 0.889 ... 1.037, so no bar
above 1 (a curved element's area exceeds its chord quad's; docs/ELEMENTS.md, "Frames turning
within an element").
"""
from __future__ import annotations

import warnings

import numpy as np

from .. import lie
from ..errors import ElementTooDistortedError, ElementWarning

__all__ = ["frame_turns", "check_frame_turns", "MAX_NORMAL_TURN", "WARN_AREA_RATIO", "MIN_AREA_RATIO", "FLAT_TURN",
           "node_windings", "whole_node_windings", "check_node_windings", "MAX_NODE_WINDING"]

#: [deg] the largest turn about the normal between two nodes' frames of one element left silent
MAX_NORMAL_TURN = 60.0
#: the element's area from its frames over its bilinear quad's below which it warns
WARN_AREA_RATIO = 0.9
#: ... below which it is an error
MIN_AREA_RATIO = 0.5
#: [deg] the same turn on a flat element, whose frames the least-turn gauge makes parallel unless
#: the user's d1 winds round a point (a vortex: the gauge keeps them as given)
FLAT_TURN = 1.0

#: [quarter turns] the most the edges' quarter turns may leave open round a node's elements, summed,
#: without a warning (``node_windings``): a cross field's singular nodes leave one (the closed cubed
#: sphere's 8 corners, Gmsh's domes' irregular nodes), a hint's spin point inside an element two
MAX_NODE_WINDING = 2

_PAIRS = ((0, 1), (1, 2), (2, 3), (3, 0), (0, 2), (1, 3))


def frame_turns(g, quads):
    """The largest turn [deg] about the element's mean normal between the frames of two of its
    nodes (m,): |log(R_a^T R_b) . n| over the node pairs of each quad.

    Parameters
    ----------
    g : (n, 4, 4) array
        The frames the element builds on; or (m, 4, 4, 4) those of each element's nodes (an
        element across a cross field's cuts: ``element_default``, "Cuts").
    quads : (m, 4) array of int
        The elements' nodes.

    Returns
    -------
    (m,) ndarray
        Turns [deg].

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.mesh.gauge import turned_about_normal
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> frame_turns(turned_about_normal(m.g0, np.radians([0.0, 90.0, 0.0, 0.0])), m.quads).round(6).tolist()
    [90.0]
    """
    g = np.asarray(g, float)
    ge = g if g.ndim == 4 else g[quads]                                # (m, 4, 4, 4)
    n = ge[:, :, :3, 2].sum(1)
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    turn = np.zeros(len(ge))
    for a, b in _PAIRS:                                                # six pairs, vectorised over elements
        w = lie.log_so3(lie.relative(ge[:, a], ge[:, b])[:, :3, :3])  # in a's frame (lie.log's w, to the bit)
        na = np.einsum("mji,mj->mi", ge[:, a, :3, :3], n)
        turn = np.maximum(turn, np.abs(np.einsum("mi,mi->m", w, na)))
    return np.degrees(turn)


def check_frame_turns(X, quads, g, j0, stacklevel=3, ids=None):
    """ElementTooDistortedError / ElementWarning for elements whose frames turn about their normal
    so that the element's reference geometry is not its quad's (module docstring).

    Parameters
    ----------
    X : (n, 3) array
        Reference positions.
    quads : (m, 4) array of int
        The elements' nodes.
    g : (n, 4, 4) or (m, 4, 4, 4) array
        The frames the element builds on (``DefaultElement.frames(mesh.g0)``), or those of each
        element's nodes (``frame_turns``).
    j0 : (m, 4) array
        The element's area element at its Gauss points (its area: the sum).
    stacklevel : int
        The warning's.
    ids : (elements (m,), nodes (n,)) arrays of int, optional
        The ids to name them by (a rank's part: the whole mesh's, ``Mesh.whole_ids``).

    Example
    -------
    >>> from core_se3 import mesh, Material
    >>> from core_se3.fem.element_default import DefaultElement
    >>> m = mesh.hemisphere_quarter(10.0, 18.0, 2, 2)
    >>> check_frame_turns(m.X, m.quads, m.g0, DefaultElement.reference_area(m, Material(1e3, 0.3, 0.1)))  # silent
    """
    P = np.asarray(X, float)[quads]
    chord = 0.5 * np.linalg.norm(np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1]), axis=1)
    ratio = np.asarray(j0, float).sum(1) / np.maximum(chord, 1e-300)
    turn = frame_turns(g, quads)
    g = np.asarray(g, float)
    d3 = (g if g.ndim == 4 else g[quads])[:, :, :3, 2]                # (m, 4, 3) the nodes' normals
    flat = np.linalg.norm(d3 - d3[:, :1], axis=2).max(1) < 1e-9
    bad = np.flatnonzero((turn > np.where(flat, FLAT_TURN, MAX_NORMAL_TURN)) | (ratio < WARN_AREA_RATIO))
    if not len(bad):
        return
    k = int(bad[np.argmin(ratio[bad])])
    el, nd = ids if ids is not None else (np.arange(len(quads)), np.arange(len(X)))
    what = (f"{len(bad)} element(s) (e.g. {el[bad[:5]].tolist()}) whose nodes' frames turn about the normal by up to "
            f"{turn[bad].max():.0f} deg (element {int(el[k])}: {turn[k]:.0f} deg, nodes {nd[np.asarray(quads)[k]].tolist()}); the "
            f"element ties its strains along its edges in these frames, and its area from them is {ratio[k]:.2f} of "
            f"its quad's (frames turning by at most {MAX_NORMAL_TURN:g} deg give 0.94 ... 1.04)"
            + (f"; on a flat element (its frames left turned by {FLAT_TURN:g} deg or more: the user's d1 winds round "
               "a point, which no gauge removes) the answer depends on them (a strip with random d1 in +-3 rad: "
               "its tip deflection 0.32 % off that of parallel frames)" if flat[k] else ""))
    fix = ("give frames whose d1 turns little within every element (d1 along the shell: a dome's meridians or "
           "parallels); a closed doubly curved surface (a sphere) has no such field of d1 (docs/ELEMENTS.md, "
           "'A mesh file's default frames')")
    if ratio[k] < MIN_AREA_RATIO:
        raise ElementTooDistortedError(f"{what}: below {MIN_AREA_RATIO:g}, the element's stiffness is not the "
                                       f"shell's there (a pressurised sphere came out -5.7 ... 7.2 times the exact "
                                       f"displacement); {fix}")
    warnings.warn(ElementWarning(f"{what}: the answer near them depends on the frames; {fix}"), stacklevel=stacklevel)


def node_windings(mesh, matching):
    """Per node (n,): the quarter turns the edges' matching leaves open round its elements, summed
    (each element's (k_b + k_r - k_t - k_l) mod 4 taken in -1 ... 2; ``element_default``, "Cuts").
    A 4-fold field's singular node leaves one quarter turn in one element round it; d1 winding by a
    whole turn round a node (a constant hint normal to the shell there) four, one in each element.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh (its elements' edges and their signs).
    matching : (E,) array of int
        The edges' quarter turns (``mesh.gauge.edge_matching``).

    Returns
    -------
    (n,) ndarray of int

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.mesh.gauge import edge_matching
    >>> m = mesh.rectangle(2.0, 2.0, 2, 2)                           # node 4 in the middle
    >>> d = m.X - m.X[4]; d[4] = (0.0, 1.0, 0.0)                     # d1 radial round it
    >>> g = mesh.frames_from(m.X, d, np.tile([0.0, 0.0, 1.0], (9, 1)))
    >>> int(node_windings(m, edge_matching(g, m.edge_nodes))[4])
    4
    """
    ks = mesh.elem_edge_sign * np.asarray(matching)[mesh.elem_edges]                # (m, 4) b, t, l, r
    q = (ks[:, 0] + ks[:, 3] - ks[:, 2] - ks[:, 1]) % 4
    q = np.where(q > 2, q - 4, q)
    w = np.zeros(mesh.n_nodes, int)
    np.add.at(w, np.asarray(mesh.quads).ravel(), np.repeat(q, 4))
    return w


def whole_node_windings(n_nodes, parts):
    """The whole mesh's :func:`node_windings` (n_nodes,) from its ranks' parts: ``parts`` a list of
    (the whole mesh's ids of a rank's local nodes, its local windings), each element on one rank,
    so a node's winding is the sum of its ranks' -- a node whose elements are split across ranks
    shows its whole winding on none of them (the closed cubed sphere with d1 the projection of +x,
    8 per face, its spin node split 2 / 2: 2 quarter turns on each rank, silent).

    Example
    -------
    >>> import numpy as np
    >>> whole_node_windings(3, [(np.array([0, 2]), np.array([2, 0])), (np.array([1, 0]), np.array([1, 2]))]).tolist()
    [4, 1, 0]
    """
    w = np.zeros(int(n_nodes), int)
    for ids, local in parts:
        np.add.at(w, np.asarray(ids, np.int64), np.asarray(local, int))
    return w


def check_node_windings(mesh, matching, stacklevel=3, windings=None):
    """ElementWarning for nodes round which the frames' d1 winds by more than MAX_NODE_WINDING
    quarter turns (``node_windings``): the elements round such a node compare their sides in frames
    turned by their actual angles (``element_default``, "Cuts"), and on a curved shell the answer
    there is off -- the closed cubed sphere (R/h 100) with d1 the projection of +x (spin points at
    two nodes, winding 4), pressurised: 1.35 / 1.20 / 1.11 times the exact displacement at them on
    8 / 16 / 24 per face (0.94 ... 1.06 beyond 30 deg of them on 16), silent before.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh.
    matching : (E,) array of int
        The edges' quarter turns.
    stacklevel : int
        The warning's.
    windings : (n,) array of int, optional
        The nodes' windings, given (the whole mesh's from its ranks': :func:`whole_node_windings`;
        ``mesh`` and ``matching`` are then not read).
    """
    w = node_windings(mesh, matching) if windings is None else np.asarray(windings)
    bad = np.flatnonzero(np.abs(w) > MAX_NODE_WINDING)
    if not len(bad):
        return
    warnings.warn(ElementWarning(
        f"the nodes' d1 wind by a whole turn round node(s) {bad[:5].tolist()}{' ...' if len(bad) > 5 else ''} "
        f"({w[bad[0]]} quarter turns round node {int(bad[0])}, above {MAX_NODE_WINDING}; a 4-fold field of d1 such "
        "as a mesh file's default frames winds by one at its singular nodes): d1 spins about the node, as the "
        "projection of a constant hint does where it is the normal, and the answer near it is off (a pressurised "
        "closed sphere whose d1 is the projection of +x: 1.20 times the exact displacement at its spin points on "
        "16 per face) -- give frames whose d1 follows the shell (a mesh file without d1_hint: d1 along its edges; "
        "docs/ELEMENTS.md, 'A mesh file's default frames')"), stacklevel=stacklevel)
