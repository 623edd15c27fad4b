"""Meshing outlines with Gmsh (the ``gmsh`` Python package from PyPI), where it is installed.

:func:`gmsh_module` imports it or says why not (the wheel needs X11/OpenGL system libraries:
``import gmsh`` can fail with an OSError, not only an ImportError).  :func:`mesh_surfaces`
meshes named OCC surfaces into quads (Frontal-Delaunay for quads, Blossom full-quad
recombination), names the boundary curves a predicate picks, writes the result as an MSH 4.1
file and reads it back through the one reader (:func:`~core_se3.mesh.from_meshio`), so that
a generated mesh and a file written by Gmsh take the same path.
"""
from __future__ import annotations

import os
import tempfile

import numpy as np

from ..errors import MeshError
from .readers import from_meshio

__all__ = ["gmsh_module", "mesh_surfaces"]

_GMSH = {}


def gmsh_module():
    """The ``gmsh`` module, or None if it is not installed or cannot load its libraries.

    Returns
    -------
    module or None

    Example
    -------
    >>> gmsh_module() is None or hasattr(gmsh_module(), "initialize")
    True
    """
    if "mod" not in _GMSH:
        try:
            import gmsh
            _GMSH["mod"] = gmsh
        except (ImportError, OSError) as exc:         # OSError: a missing libGLU, libXcursor, ...
            _GMSH["mod"], _GMSH["why"] = None, f"{type(exc).__name__}: {exc}"
    return _GMSH["mod"]


def mesh_surfaces(build, size, curves=None, points=None, save=None):
    """Quad mesh of plane surfaces built with Gmsh's OCC kernel, with named groups.

    Parameters
    ----------
    build : callable
        ``build(occ) -> {region name: [surface tags]}``: adds the surfaces (in the x-y plane,
        normal +z) with ``gmsh.model.occ``; they are fragmented together so that the mesh
        conforms across region boundaries (a surface may be listed in several regions).
    size : float
        Target element size [length].
    curves : dict, optional
        name -> predicate(the point (3,) in the middle of a curve's parameter range) -> bool,
        choosing the boundary curves of a named node set (a physical curve).
    points : dict, optional
        name -> predicate(position (3,)) -> bool choosing geometry points (a physical point).
    save : str or path-like, optional
        Keep the MSH 4.1 file there (default: a temporary file, removed).

    Returns
    -------
    Mesh
        Read back with :func:`~core_se3.mesh.from_meshio`.

    Example
    -------
    >>> g = gmsh_module()
    >>> if g is not None:
    ...     m = mesh_surfaces(lambda occ: {"sq": [occ.addRectangle(0, 0, 0, 1, 1)]}, 0.5,
    ...                       curves={"left": lambda c: abs(c[0]) < 1e-9})
    ...     print(m.n_elements >= 4, sorted(m.regions), sorted(m.edges))
    ... else:
    ...     print(True, ['sq'], ['left'])
    True ['sq'] ['left']
    """
    gmsh = gmsh_module()
    if gmsh is None:
        raise MeshError(f"the Gmsh backend needs the gmsh package ({_GMSH.get('why')}); "
                        "pip install gmsh, or use backend=\"structured\"")
    if not (np.isfinite(size) and size > 0):
        raise MeshError(f"element size must be positive, got {size}")
    if gmsh.isInitialized():
        raise MeshError("gmsh is already initialised by the caller: finalize it first")
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("core_se3")
        occ = gmsh.model.occ
        regions = build(occ)
        tags = sorted({t for ts in regions.values() for t in ts})
        pieces = {t: [t] for t in tags}
        if len(tags) > 1:
            _, children = occ.fragment([(2, t) for t in tags], [])
            pieces = {t: [e[1] for e in kids] for t, kids in zip(tags, children)}
        occ.synchronize()
        for name, ts in regions.items():
            gmsh.model.addPhysicalGroup(2, sorted({p for t in ts for p in pieces[t]}), name=name)
        for name, pred in (curves or {}).items():
            sel = [t for _, t in gmsh.model.getEntities(1) if pred(_midpoint(gmsh, t))]
            if sel:
                gmsh.model.addPhysicalGroup(1, sel, name=name)
        for name, pred in (points or {}).items():
            sel = [t for _, t in gmsh.model.getEntities(0) if pred(np.asarray(gmsh.model.getValue(0, t, [])))]
            if sel:
                gmsh.model.addPhysicalGroup(0, sel, name=name)
        for opt, val in (("Mesh.MeshSizeMax", size), ("Mesh.MeshSizeMin", size / 4),
                         ("Mesh.Algorithm", 8), ("Mesh.RecombineAll", 1),
                         ("Mesh.RecombinationAlgorithm", 3), ("Mesh.MshFileVersion", 4.1)):
            gmsh.option.setNumber(opt, val)
        gmsh.model.mesh.generate(2)
        if save is not None:
            path = os.fspath(save)
            gmsh.write(path)
        else:
            fd, path = tempfile.mkstemp(suffix=".msh")
            os.close(fd)
            gmsh.write(path)
    finally:
        gmsh.finalize()
    try:
        return from_meshio(path, triangles="split")
    finally:
        if save is None:
            os.unlink(path)


def _midpoint(gmsh, tag):
    lo, hi = gmsh.model.getParametrizationBounds(1, tag)
    return np.asarray(gmsh.model.getValue(1, tag, [(lo[0] + hi[0]) / 2]), float)
