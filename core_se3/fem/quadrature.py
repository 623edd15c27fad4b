"""Bilinear shape functions and the 2x2 Gauss rule on the reference square [-1, 1]^2.

Natural coordinates of the corners (-1,-1), (1,-1), (1,1), (-1,1) (counter-clockwise); every
Gauss weight is 1.
"""
from __future__ import annotations

import numpy as np

__all__ = ["GAUSS_2x2", "shape_functions", "surface_jacobian"]

_G = 1.0 / np.sqrt(3.0)
GAUSS_2x2 = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])


def shape_functions(points=GAUSS_2x2):
    """Bilinear N (q, 4) and dN/dx, dN/dy (q, 2, 4) at natural points (q, 2).

    Parameters
    ----------
    points : (q, 2) array, optional
        Natural coordinates (x, y) in [-1, 1]^2; default the 2x2 Gauss points ``GAUSS_2x2``.

    Returns
    -------
    N : (q, 4) ndarray
        Shape functions of the corners (-1,-1), (1,-1), (1,1), (-1,1).
    dN : (q, 2, 4) ndarray
        Their derivatives with respect to x and y.

    Example
    -------
    >>> import numpy as np
    >>> N, dN = shape_functions(np.zeros((1, 2)))
    >>> N.tolist(), dN[0].sum(axis=1).tolist()
    ([[0.25, 0.25, 0.25, 0.25]], [0.0, 0.0])
    """
    xs = np.array([-1, 1, 1, -1.0])
    ys = np.array([-1, -1, 1, 1.0])
    x, y = points[:, :1], points[:, 1:]
    N = 0.25 * (1 + x * xs) * (1 + y * ys)
    dN = np.stack([0.25 * xs * (1 + y * ys), 0.25 * ys * (1 + x * xs)], 1)
    return N, dN


def surface_jacobian(X, dN):
    """Area element j0 = |a_1 x a_2| (m, q) of bilinear quads with corner positions X (m, 4, 3)
    at the points of the shape-function derivatives dN (q, 2, 4): dA = j0 dxi1 dxi2.

    Parameters
    ----------
    X : (m, 4, 3) array
        Corner positions [length] of m quads.
    dN : (q, 2, 4) array
        Shape-function derivatives at q points (:func:`shape_functions`).

    Returns
    -------
    (m, q) ndarray
        j0 [length^2 per unit natural area]; with the unit Gauss weights, j0.sum(axis=1) is the
        area of each quad.

    Example
    -------
    >>> import numpy as np
    >>> X = np.array([[[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0.0]]])
    >>> surface_jacobian(X, shape_functions()[1]).round(12).tolist()   # area 2 = 4 points x 0.5
    [[0.5, 0.5, 0.5, 0.5]]
    """
    X = np.asarray(X)
    # the corners relative to the first (dN's rows sum to 0): a_1, a_2 from differences of
    # nearby positions, exact, not from sums of positions of size |X| (eps |X| / h of them lost
    # for a part far from the origin: the areas, and so the dipoles, 8.9e-8 off at 1e9)
    a = np.einsum("qai,mij->mqaj", dN, X - X[:, :1])          # (m, q, 2, 3) tangents a_1, a_2
    return np.linalg.norm(np.cross(a[:, :, 0], a[:, :, 1]), axis=-1)
