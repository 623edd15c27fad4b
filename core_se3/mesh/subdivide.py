"""Conforming subdivision of a mixed quad/triangle surface mesh into quads only.

Quad-dominant meshes (Gmsh's recombination leaves some triangles) become all-quad meshes by one
step of the Catmull-Clark split: a node at the midpoint of every element edge and at every
element centroid; each quad becomes 4 quads and each triangle 3, line cells 2 segments, with the
node order (orientation) of the parent kept.  The result is conforming because neighbouring
cells share their edge midpoints.  New nodes lie on chords (not on a curved CAD surface).
"""
from __future__ import annotations

import numpy as np

__all__ = ["split_to_quads"]


def split_to_quads(X, blocks):
    """Split every quad, triangle and line cell of ``blocks`` (conforming, orientation kept).

    Parameters
    ----------
    X : (n, 3) array
        Node positions [length].
    blocks : list of (str, (k, p) int array)
        Cell blocks ("quad", "triangle", "line", "vertex"); other types are returned unchanged.

    Returns
    -------
    X2 : (n2, 3) ndarray
        The old nodes first (same ids), then the edge midpoints and the cell centroids.
    blocks2 : list of (str, ndarray)
        One block per input block: quads for quads and triangles (4 and 3 children per cell,
        in the parent's order), 2 segments per line, vertices unchanged.
    children : list of (k, c) ndarray
        For every input block the ids (within the output block) of each cell's children.

    Example
    -------
    >>> import numpy as np
    >>> X = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]])
    >>> X2, out, kids = split_to_quads(X, [("quad", np.array([[0, 1, 2, 3]])),
    ...                                    ("triangle", np.array([[1, 4, 2]])), ("line", np.array([[1, 2]]))])
    >>> [(t, len(c)) for t, c in out], len(X2)                 # 4 + 3 quads, 2 segments; 5 + 6 midpoints + 2 centres
    ([('quad', 4), ('quad', 3), ('line', 2)], 13)
    >>> X2[out[2][1][0, 1]].tolist()                            # the shared midpoint of edge (1, 2)
    [1.0, 0.5, 0.0]
    """
    X = np.asarray(X, float)
    n = len(X)
    pairs = []
    for typ, c in blocks:
        c = np.asarray(c, np.int64)
        if typ in ("quad", "triangle", "line"):
            k = c.shape[1]
            cyc = [(i, (i + 1) % k) for i in range(k)] if typ != "line" else [(0, 1)]
            for a, b in cyc:
                pairs.append(np.sort(np.stack([c[:, a], c[:, b]], 1), axis=1))
    pairs = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
    uniq, _ = np.unique(pairs, axis=0, return_inverse=True) if len(pairs) else (pairs, None)
    mid_id = {tuple(e): n + i for i, e in enumerate(uniq.tolist())}
    new = [X, 0.5 * (X[uniq[:, 0]] + X[uniq[:, 1]])] if len(uniq) else [X]
    next_id = n + len(uniq)

    def mid(a, b):
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return np.array([mid_id[(int(x), int(y))] for x, y in zip(lo, hi)], np.int64)

    out, children = [], []
    for typ, c in blocks:
        c = np.asarray(c, np.int64)
        if typ == "line":
            m = mid(c[:, 0], c[:, 1])
            seg = np.stack([np.stack([c[:, 0], m], 1), np.stack([m, c[:, 1]], 1)], 1).reshape(-1, 2)
            out.append(("line", seg))
            children.append(np.arange(2 * len(c)).reshape(-1, 2))
        elif typ in ("quad", "triangle"):
            k = c.shape[1]
            C = next_id + np.arange(len(c))
            next_id += len(c)
            new.append(X[c].mean(1))
            ms = [mid(c[:, i], c[:, (i + 1) % k]) for i in range(k)]     # ms[i]: edge i -> i+1
            # child at corner i: (corner i, mid of edge i, centre, mid of edge i-1)
            kids = [np.stack([c[:, i], ms[i], C, ms[i - 1]], 1) for i in range(k)]
            out.append(("quad", np.stack(kids, 1).reshape(-1, 4)))
            children.append(np.arange(k * len(c)).reshape(-1, k))
        else:
            out.append((typ, c))
            children.append(np.arange(len(c)).reshape(-1, 1))
    return np.concatenate(new), out, children
