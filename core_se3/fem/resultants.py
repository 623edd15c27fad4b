"""Stress resultants at element centres, for output (VTU cell fields).

The energy density W(eps) (material.py) is per unit reference area with eps = zeta - zeta0 the
strain twists (c_a, k_a) in the body frame.  Its conjugates S^a = dW/d eps_a = (s^a, t^a) give
the force and moment transmitted across a reference cut with unit conormal nu (tangent to the
reference surface), per unit reference length of the cut:

    n(nu) = sum_a (nu . A_a) s^a,        m(nu) = sum_a (nu . A_a) t^a

(A_a: reference tangents, the translational parts of zeta0_a; for a membrane W = 1/2 N:e
this is n(nu) = N^ab nu_a A_b, the usual traction).  Reported for the two cuts nu = the
reference directors d1 and d2 at the centre, as lab vectors ``N1``, ``N2`` (force/length)
and ``M1``, ``M2`` (moment/length, = force), and as components along the current directors
(``N1_local`` = (N11, N12, Q1), ``N2_local`` = (N21, N22, Q2), ``M1_local``, ``M2_local``: a
moment's components along d1, d2, d3 -- twisting, bending, drilling for the cut normal to d1).
Sign: the force and moment that the material on the +nu side exerts on the material behind the
cut (a cantilever along x under a tip force P on z, width w: N1 = (0, 0, P/w),
M1 = (0, -(L - x) P/w, 0); tests/test_result_outputs.py checks these on rectangles, a distorted
mesh and a cylinder panel).

The cuts' normals are reported with them, as the cell fields ``cut_d1`` and ``cut_d2`` (m, 3):
the reference unit conormals (lab) of the cuts of N1, M1 and of N2, M2.  They are the user's d1,
d2 at the centre (the mean rotation of the element's nodal frames), except across a cross
field's cuts.  Across a cross field's cuts (a mesh file's default frames on a closed surface,
``fem.element_default``, "Cuts") an element's nodes' d1 differ by quarter turns and have no mean:
its strains and resultants are in the frames it compares its sides in, its nodes' turned by the
quarter turns that leave them least turned from its first node's (round a singular node, turned
to the first node's d1 by their actual angles), so N1 may be across any of the four directions
of the user's cross there and which one depends on the element's first node -- ``cut_d1`` says
which (the closed cubed sphere from a file, 4 per face: on 30 of its 96 elements cut_d1 is not
the centre mean of the user's d1; its nodes rotated by one place, N1 changes by 52 % and
N1 (x) cut_d1 + N2 (x) cut_d2 by 1e-8).
"""
from __future__ import annotations

import numpy as np

from ..lie import mean_rotation
from .material import law_matrix

__all__ = ["element_resultants"]

CENTRE = np.zeros((1, 2))


def _centre_frames(element, frames):
    """(R, C): the centre frames R (m, 3, 3) in which the strains of ``element`` at the nodal
    frames (n, 4, 4) are, and C (m, 3, 3) taking the frame whose d1, d2 are the cuts' normals into
    them (None: R's own d1, d2) -- the user's frames, turned by the element's quarter turns S
    across a cross field's cuts (module docstring, "Across a cross field's cuts")."""
    mesh = element.mesh
    R = mean_rotation(frames[mesh.quads, :3, :3])
    C = None
    to_element = getattr(element, "frames", None)
    if getattr(element, "matching", None) is not None:
        # across a cross field's cuts the nodes' d1 of an element differ by quarter turns: the
        # strains and the resultants are in the frames it compares its sides in (those of its
        # first node's d1 family, ``element_default``, "Cuts"), g Q S; with a gauge Q too (a flat
        # or developable part beside a doubly curved one with cuts), C = Re^T R takes the user's
        # frames turned by the same quarter turns S into them, as without cuts (before, the
        # gauged part's resultants were across the element's d1: an annulus' N1 moved by 35 %
        # when a part with cuts was added to its mesh)
        corner = element.corner_frames(frames)[..., :3, :3]                   # (m, 4, 3, 3)
        R = mean_rotation(corner)
        if to_element is not None and to_element(frames) is not frames:
            S = np.einsum("mnji,mnjk->mnik", to_element(frames)[mesh.quads, :3, :3], corner)
            user = mean_rotation(np.einsum("mnij,mnjk->mnik", frames[mesh.quads, :3, :3], S))
            C = np.einsum("mji,mjk->mik", R, user)
    elif to_element is not None and to_element(frames) is not frames:
        # the strains are in the element's frames (turned about the normal, ``mesh.gauge``):
        # C = Re^T R takes the user's centre frame R into the element's Re
        Re = mean_rotation(to_element(frames)[mesh.quads, :3, :3])
        C, R = np.einsum("mji,mjk->mik", Re, R), Re
    return R, C


def element_resultants(element, g, increments=None):
    """Cell fields (name -> (m, 3)) of the default element at state g (n, 4, 4).

    Parameters
    ----------
    element : DefaultElement
        The element (its mesh and material law; anything with ``strains(g, points)``, and
        ``linear_strains(eta, points)`` for ``increments``).
    g : (n, 4, 4) array
        Current nodal frames.
    increments : (n, 6) array, optional
        A linear analysis' nodal increments eta about the reference (its state g): the strains
        are linearised (``linear_strains``) and the resultants taken in the reference frames.
        The strains of the state itself are not the linear ones: a cantilever's linear tip
        deflection of a third of its length stretches the chords of its linear state, whose
        membrane force read 1.4e4 where the linear one is 0 (the shear force 1).

    Returns
    -------
    dict
        ``N1``, ``N2`` [force/length] and ``M1``, ``M2`` [force] as lab vectors, and
        ``N1_local`` ... ``M2_local`` along the current directors, and ``cut_d1``, ``cut_d2``
        the cuts' reference unit normals as lab vectors (module docstring), each (m, 3), at the
        element centres.

    Example
    -------
    >>> from core_se3 import mesh, Material, fem
    >>> el = fem.DefaultElement(mesh.rectangle(1.0, 1.0, 2, 1), Material(1.0e3, 0.3, 0.01))
    >>> sorted(element_resultants(el, el.mesh.g0))[:3]
    ['M1', 'M1_local', 'M2']
    >>> el = fem.DefaultElement(el.mesh, Material(1.0e3, 0.0, 0.01))
    >>> g = el.mesh.g0.copy(); g[:, 0, 3] *= 1.01        # stretch 0.01: N11 = E h eps = 0.1
    >>> element_resultants(el, g)["N1"].round(12).tolist()
    [[0.1, 0.0, 0.0], [0.1, 0.0, 0.0]]
    """
    mesh = element.mesh
    zeta0 = element.strains(mesh.g0, CENTRE)[:, 0]            # (m, 12) body frame
    if increments is None:
        eps = element.strains(g, CENTRE)[:, 0] - zeta0
        frames = g                                            # current centre frame
    else:                                                     # linear analysis: the reference frames
        eps = element.linear_strains(increments, CENTRE)[:, 0]
        frames = mesh.g0
    R, C = _centre_frames(element, frames)
    R0, C0 = (R, C) if frames is mesh.g0 else _centre_frames(element, mesh.g0)
    A1, A2 = zeta0[:, 0:3], zeta0[:, 6:9]
    D, _ = law_matrix(element.material, A1, A2, element.size)  # (m, 12, 12)
    S = np.einsum("mij,mj->mi", D, eps)
    s = (S[:, 0:3], S[:, 6:9])                                # force conjugates
    t = (S[:, 3:6], S[:, 9:12])                               # moment conjugates
    A = np.stack([A1, A2], 1)                                 # (m, 2, 3)
    out = {}
    for k, nu in ((1, np.array([1.0, 0, 0])), (2, np.array([0, 1.0, 0]))):
        w = A @ nu if C is None else np.einsum("mai,mi->ma", A, C[:, :, k - 1])   # (m, 2): nu . A_a
        n_loc = w[:, :1] * s[0] + w[:, 1:] * s[1]
        m_loc = w[:, :1] * t[0] + w[:, 1:] * t[1]
        out[f"N{k}"] = np.einsum("mij,mj->mi", R, n_loc)
        out[f"M{k}"] = np.einsum("mij,mj->mi", R, m_loc)
        out[f"N{k}_local"] = n_loc if C is None else np.einsum("mji,mj->mi", C, n_loc)
        out[f"M{k}_local"] = m_loc if C is None else np.einsum("mji,mj->mi", C, m_loc)
        out[f"cut_d{k}"] = R0[:, :, k - 1] if C0 is None else np.einsum("mij,mj->mi", R0, C0[:, :, k - 1])
    return out
