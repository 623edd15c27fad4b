"""The mixed (MIP) iteration's kernels of the default element (numba): the element stresses
linearised about the last evaluated state, f = Dbar (z(g) - z0 + G eta), G = dz/deta
(``fem.element_default.DefaultElement.linear_stress``), and the conversions between element
stresses (m, 24) and their signed per-edge parts (m, 4, 6) that the tangent drivers of
``kernels.element`` read (fe, fe_geo).
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from .element_ops import CHUNK, element_stress_lin

__all__ = ["element_linear_stress", "element_linear_stress_serial", "signed_edge_stress", "stress_from_signed"]


@njit(cache=True, parallel=True)
def element_linear_stress(quads, elem_edges, elem_edge_sign, Rk, Dbar, z0, psi, coef, eta, out):
    """Linearised element stresses, parallel over elements.

    Parameters
    ----------
    quads (m,4), elem_edges (m,4), elem_edge_sign (m,4) : mesh topology
    Rk (E,3,3) : the edges' quarter turns across a cross field's cuts, or empty (0,3,3)
        (``element_ops.match_G``)
    Dbar (m,300) packed (``element_ops.unpack_sym``), z0 (m,24) : the element's constant data
    psi (E,6), coef (E,3) : edge twists and their coefficients at the state (the workspace of
        the last ``element_residual``/``element_tangent`` call)
    eta (n,6) : nodal increments (g <- g exp(eta))
    out (m,24) : written, Dbar (z - z0 + G eta)
    """
    m = quads.shape[0]
    nch = (m + CHUNK - 1) // CHUNK
    for ch in prange(nch):
        G = np.empty((4, 2, 6, 6))
        w = np.empty(24)
        D = np.empty((24, 24))
        for el in range(ch * CHUNK, min(m, (ch + 1) * CHUNK)):
            element_stress_lin(el, quads, elem_edges, elem_edge_sign, Rk, Dbar, z0, psi, coef, eta, G, w, D, out)


@njit(cache=True)
def element_linear_stress_serial(quads, elem_edges, elem_edge_sign, Rk, Dbar, z0, psi, coef, eta, out):
    """``element_linear_stress`` in one thread (same parameters)."""
    G = np.empty((4, 2, 6, 6))
    w = np.empty(24)
    D = np.empty((24, 24))
    for el in range(quads.shape[0]):
        element_stress_lin(el, quads, elem_edges, elem_edge_sign, Rk, Dbar, z0, psi, coef, eta, G, w, D, out)


def signed_edge_stress(stress, sign, out):
    """out (m,4,6) = sign[el,k] * stress[el, 6k:6k+6]: element stresses (m,24) as the signed
    per-edge parts the tangent drivers read (fe_geo).

    Parameters
    ----------
    stress : (m, 24) array_like (any shape of that size, like ``DefaultElement.evaluate``)
    sign : (m, 4) int, ``mesh.elem_edge_sign``
    out : (m, 4, 6) float array, written and returned
    """
    m = sign.shape[0]
    S = np.asarray(stress, dtype=float)
    if S.size != 24 * m:
        raise ValueError(f"stress must have shape ({m}, 24), got {S.shape}")
    np.multiply(sign[..., None], S.reshape(m, 4, 6), out=out)
    return out


def stress_from_signed(fe, sign):
    """The element stresses f (m,24) (a new array) from their signed per-edge parts fe (m,4,6),
    fe[el,k,i] = sign[el,k] f[el,6k+i] (exact: the signs are +-1).

    Parameters
    ----------
    fe : (m, 4, 6) float array (the drivers' workspace)
    sign : (m, 4) int, ``mesh.elem_edge_sign``
    """
    m = sign.shape[0]
    out = np.empty((m, 24))
    np.multiply(sign[..., None], fe, out=out.reshape(m, 4, 6))
    return out
