"""The storage forms of the default element's stiffness Dbar in the kernels (numba): packed upper
triangles (m, 300), the order z' of the 24 edge-twist components (``ZP``), the split form of a law
without v-w coupling (with the membrane-drilling columns of distorted quads), the per-element
choice between it and the unpacked Dbar (``element_D``), and the packed product
(``element_ops``' module docstring on the material block).
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["NSYM", "ZP", "split_form", "unpack_sym", "unpack_perm", "element_D", "packed_matvec"]

NSYM = 300                          # entries of a symmetric 24x24 matrix's upper triangle


@njit(cache=True)
def unpack_sym(Dp, el, D):
    """D (24,24) <- the symmetric matrix whose upper triangle, row by row, is Dp[el] (300,)
    (the element's Dbar is stored packed: 2.4 kB instead of 4.6 kB per element)."""
    k = 0
    for a in range(24):
        for b in range(a, 24):
            v = Dp[el, k]
            D[a, b] = v
            D[b, a] = v
            k += 1


# The kernels' order z' of an element's 24 edge-twist components (z_b, z_t, z_l, z_r; (v, w)
# each): the v of the four edges, then their w.  ZP[6k + i]: component i of edge k in z'.
ZP = np.array([3 * (a // 6) + a % 6 if a % 6 < 3 else 9 + 3 * (a // 6) + a % 6 for a in range(24)], np.int64)


def _packed(a, b):
    """Position of the entry (a, b) of a symmetric 24x24 matrix in its packed upper triangle."""
    a, b = np.minimum(a, b), np.maximum(a, b)
    return a * 24 - a * (a - 1) // 2 + (b - a)


_IU = np.triu_indices(24)
_DRILL = (_IU[0] % 6 == 5) | (_IU[1] % 6 == 5)                       # an edge's drilling component w_3
VW_INDEX = np.flatnonzero((_IU[0] % 6 < 3) != (_IU[1] % 6 < 3))      # the packed v-w entries (144)
VW_OTHER = np.flatnonzero(((_IU[0] % 6 < 3) != (_IU[1] % 6 < 3)) & ~_DRILL)   # those not with a w_3 (96)
# SPLIT_INDEX[r, c]: the packed entry of D'[r, c'] (z' indices; c' = c for the v rows r < 12, 12 + c
# for the w rows): Dbar[:, SPLIT_INDEX] (m, 24, 12) = the diagonal blocks Dvv, Dww, stacked
SPLIT_INDEX = _packed(np.argsort(ZP)[:, None], np.argsort(ZP)[np.arange(24)[:, None] // 12 * 12 + np.arange(12)])
# DRILL_INDEX[r, k]: the packed entry of D'[r, 14 + 3k] (v row r < 12 with the w_3 of edge k)
DRILL_INDEX = _packed(np.argsort(ZP)[:12, None], 6 * np.arange(4)[None, :] + 5)


def split_form(Dp):
    """The v/w split form of packed element stiffnesses Dp (m, 300), or None.

    A law whose membrane and shear act only on the translational parts v of the strain twists
    and bending and drilling only on the rotational parts w (every law of ``fem.material``)
    gives a Dbar with exactly zero v-w blocks: in the order z' = (v_b, v_t, v_l, v_r, w_b, w_t,
    w_l, w_r) (``ZP``), Dbar = diag(Dvv, Dww), read by the kernels as (m, 24, 12) (row r of z'
    over its own half: 2.3 kB per element, no unpacking).  On distorted quads the membrane
    strain also sees the edges' drilling components w_3 (``fem.membrane_drilling``): the v-w
    blocks are then zero except in those 4 columns, and the form is (m, 24, 16), the v rows
    carrying their coupling Dc (12 x 4) with the w_3 of the 4 edges in columns 12..15 (the w
    rows' coupling is its transpose; their last 4 columns are zero).  A law coupling v and w
    otherwise gives None: the kernels then unpack the whole Dbar per element (``unpack_perm``).

    Parameters
    ----------
    Dp : (m, 300) float array
        Upper triangles, row by row (``DefaultElement.Dbar_packed``).

    Returns
    -------
    (m, 24, 12) float array or None
        Exactly zero v-w entries are required (a test on the values, not a tolerance).

    Example
    -------
    >>> import numpy as np
    >>> Dp = np.zeros((1, 300))
    >>> Dp[0, _packed(np.arange(24), np.arange(24))] = np.arange(24.0)     # diag(0, 1, ..., 23)
    >>> Ds = split_form(Dp)
    >>> Ds.shape, float(Ds[0, 3, 3]), float(Ds[0, 12, 0])   # z'[3]: v_0 of edge 1, z'[12]: w_0 of edge 0
    ((1, 24, 12), 6.0, 3.0)
    >>> Dp[0, _packed(0, 5)] = 2.0                   # couple v_0 and w_3 of edge 0: the drilling form
    >>> Ds = split_form(Dp)
    >>> Ds.shape, float(Ds[0, 0, 12]), float(Ds[0, 12, 12])
    ((1, 24, 16), 2.0, 0.0)
    >>> Dp[0, _packed(0, 3)] = 1.0                   # couple v_0 and w_0 of edge 0
    >>> split_form(Dp) is None
    True
    """
    Dp = np.asarray(Dp, dtype=float)
    if Dp[:, VW_OTHER].any():
        return None
    Ds = Dp[:, SPLIT_INDEX]
    if Dp[:, VW_INDEX].any():
        Ds = np.concatenate([Ds, np.zeros((len(Dp), 24, 4))], 2)
        Ds[:, :12, 12:] = Dp[:, DRILL_INDEX]
    return np.ascontiguousarray(Ds)


@njit(cache=True)
def unpack_perm(Dp, el, D):
    """D (24,24) <- element el's Dbar (packed Dp[el], 300,) in the order z' (``ZP``): D[ZP[a],
    ZP[b]] = Dbar[a, b] (the general path, for a law that couples v and w)."""
    k = 0
    for a in range(24):
        pa = ZP[a]
        for b in range(a, 24):
            pb = ZP[b]
            v = Dp[el, k]
            D[pa, pb] = v
            D[pb, pa] = v
            k += 1


@njit(cache=True, inline="always")
def element_D(Dbar, Dsplit, el, D):
    """Element el's stiffness in the order z', as the rows the kernels read: Dsplit[el] (24, 12)
    (row r over its own half, v or w: ``split_form``) when Dsplit holds the split form, else
    the whole Dbar unpacked into the workspace D (24, 24) (Dsplit empty, (0, 24, 12))."""
    if Dsplit.shape[0] == 0:
        unpack_perm(Dbar, el, D)
        return D
    return Dsplit[el]


@njit(cache=True)
def packed_matvec(Dp, x, out):
    """out[el] = Dbar[el] x[el] for every element, Dbar packed (m, 300), x (m, 24)."""
    for el in range(Dp.shape[0]):
        for a in range(24):
            out[el, a] = 0.0
        k = 0
        for a in range(24):
            out[el, a] += Dp[el, k] * x[el, a]
            k += 1
            for b in range(a + 1, 24):
                v = Dp[el, k]
                out[el, a] += v * x[el, b]
                out[el, b] += v * x[el, a]
                k += 1
