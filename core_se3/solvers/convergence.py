"""Unit-scaled norms and the convergence test of every Newton iteration.

Convergence is judged on unit-scaled norms so that N-mm and SI problems and L/h = 1e4 behave
alike: moments are divided by a characteristic length ``ell`` (the bounding-box diagonal),
rotations of the increment are multiplied by it, and both norms are relative:

    |r_free|_s <= rtol * max(|f_ext|_s, |r_int|_s, |lam q|_s)   and   |eta|_s <= dtol * ell,

with the residual's round-off floor 1e3 eps (force scale of the element)/scale as a lower
bound on rtol (the terms that cancel in r = Dbar (z - z0) are ~ Dbar z).
"""
from __future__ import annotations

import numpy as np

__all__ = ["scaled_norm", "relative_residual", "increment_norm"]


def scaled_norm(r, ell, moment=True):
    """Norm of nodal 6-vectors with the rotational part divided by ell (moments; ``moment``)
    or multiplied by it (rotations of an increment).

    Parameters
    ----------
    r : array_like
        Nodal 6-vectors, any shape with 6n entries (n, 6) or (6n,).
    ell : float
        The characteristic length [length] (``Problem.length_scale``).
    moment : bool, optional
        True: forces and moments (moments / ell); False: increments (rotations x ell).

    Returns
    -------
    float
        [force] or [length].

    Example
    -------
    >>> import numpy as np
    >>> float(scaled_norm(np.array([3.0, 0, 0, 0, 0, 8.0]), ell=2.0))
    5.0
    """
    r = np.asarray(r, dtype=float).reshape(-1, 2, 3)        # (node, force/moment, component)
    w = np.array([1.0, ell ** -2 if moment else ell ** 2])
    # one pass: sum_n,k w_k |r_nk|^2 (this runs several times per Newton iteration)
    return np.sqrt(np.einsum("nkc,nkc,k->", r, r, w))


def relative_residual(asm, ev, ell, extra_scale=0.0):
    """(relative residual, its round-off floor) of an Evaluation ``ev`` on the assembler's free
    dofs; ``extra_scale`` (e.g. |lam q|_s of continuation) joins the scale.

    Parameters
    ----------
    asm : core_se3.assembly.Assembler
        The free dofs (``Problem.assembler()``).
    ev : core_se3.model.Evaluation
        The equations at the state.
    ell : float
        The length scale of :func:`scaled_norm`.
    extra_scale : float, optional
        A further force scale.

    Returns
    -------
    (float, float)
        |r|_s / max(|f_ext|_s, |r_int|_s, extra_scale), and 1e3 eps force_scale / that scale
        (at most 1e300).

    Example
    -------
    At the reference state r = -f_ext, so the relative residual is 1:

    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> rn, floor = relative_residual(p.assembler(), p.evaluate(p.mesh.g0, 1.0), p.length_scale)
    >>> round(float(rn), 12), bool(floor < 1e-6)
    (1.0, True)
    """
    scale = max(scaled_norm(ev.f_ext, ell), scaled_norm(ev.r_int, ell), extra_scale, 1e-300)
    rn = scaled_norm(asm.scatter(ev.r), ell) / scale
    # at most 1e300 (the floor where nothing is loaded or stressed, scale 1e-300): that of a
    # stressed reference (a curved shell at lam = 0) overflowed to inf with a bare NumPy
    # RuntimeWarning once its force scale passed ~1e21 (the Sze roof in micrometres, E in Pa)
    top = 1e3 * np.finfo(float).eps * ev.force_scale
    floor = float(top / scale) if float(scale) * 1e300 > top else 1e300    # (Python floats: inf, no warning)
    return rn, floor


def increment_norm(eta, ell):
    """|eta|_s / ell of nodal increments (n, 6): the relative size the dtol test uses.

    Parameters: eta (n, 6) increments [length, rad]; ell [length].  Returns: float [-].

    Example
    -------
    >>> import numpy as np
    >>> float(increment_norm(np.array([[0.3, 0, 0, 0, 0, 0.2]]), ell=2.0))     # sqrt(0.3^2 + 0.4^2) / 2
    0.25
    """
    return scaled_norm(eta, ell, moment=False) / ell
