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

    Example
    -------
    >>> import numpy as np
    >>> float(scaled_norm(np.array([3.0, 0, 0, 0, 0, 8.0]), ell=2.0))
    5.0
    """
    r = np.asarray(r).reshape(-1, 6)
    if moment:
        return np.sqrt(np.sum(r[:, :3] ** 2) + np.sum((r[:, 3:] / ell) ** 2))
    return np.sqrt(np.sum(r[:, :3] ** 2) + np.sum((r[:, 3:] * ell) ** 2))


def relative_residual(asm, ev, ell, extra_scale=0.0):
    """(relative residual, its round-off floor) of an Evaluation ``ev`` on the assembler's free
    dofs; ``extra_scale`` (e.g. |lam q|_s of continuation) joins the scale."""
    scale = max(scaled_norm(ev.f_ext, ell), scaled_norm(ev.r_int, ell), extra_scale, 1e-300)
    rn = scaled_norm(asm.scatter(ev.r), ell) / scale
    floor = 1e3 * np.finfo(float).eps * ev.force_scale / scale
    return rn, floor


def increment_norm(eta, ell):
    """|eta|_s / ell of nodal increments (n, 6): the relative size the dtol test uses."""
    return scaled_norm(eta, ell, moment=False) / ell
