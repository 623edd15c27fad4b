"""Further structured shell meshes for the Sze et al. (2004) suite.

``hemisphere_quarter``: a quarter of a hemisphere with a polar hole,
phi0 = R (sin t cos f, sin t sin f, cos t), polar angle t in [t_hole, pi/2], azimuth
f in [0, pi/2].  xi1 = t (edges 'x0' = the hole, 'x1' = the equator), xi2 = f ('y0' on the
plane y = 0, 'y1' on the plane x = 0).  Frames: d1 = e_t (meridian, toward the equator),
d2 = e_f, d3 = d1 x d2 = the outward normal e_r.
(Flat, cylindrical and annular meshes are in core_se3.mesh.)
"""
from __future__ import annotations

import numpy as np

from .errors import MeshError
from .mesh import Mesh, _structured, frames_from

__all__ = ["hemisphere_quarter"]


def hemisphere_quarter(R, hole_deg, nt, nf):
    """Quarter hemisphere of radius R with a polar hole of half-angle ``hole_deg`` [deg]."""
    if not (R > 0 and 0 < hole_deg < 90):
        raise MeshError("hemisphere_quarter needs R > 0 and 0 < hole_deg < 90")
    ids, quads, edges = _structured(nt, nf)
    t = np.linspace(np.radians(hole_deg), np.pi / 2, nt + 1)
    f = np.linspace(0.0, np.pi / 2, nf + 1)
    TT, FF = np.meshgrid(t, f)
    T, F = TT.ravel(), FF.ravel()
    X = R * np.stack([np.sin(T) * np.cos(F), np.sin(T) * np.sin(F), np.cos(T)], -1)
    d1 = np.stack([np.cos(T) * np.cos(F), np.cos(T) * np.sin(F), -np.sin(T)], -1)
    d3 = X / R
    return Mesh(frames_from(X, d1, d3), quads, edges, shape=(nt, nf))
