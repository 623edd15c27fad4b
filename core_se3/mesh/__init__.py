"""Layer 1, meshes: the :class:`Mesh` (nodal reference frames, quads, named node sets and element
regions), structured generators, and the file reader.

Example
-------
>>> from core_se3 import mesh
>>> m = mesh.rectangle(10.0, 1.0, 4, 1)
>>> sorted(m.edges)
['x0', 'x1', 'y0', 'y1']
"""
from .core import LOCAL_EDGES, Mesh, chain_order, frames_from
from .generators import annulus, cross, cylinder_arch, cylinder_panel, hemisphere_quarter, rectangle
from .readers import from_meshio, read_meshio
from .refine import carry_held, carry_nodes, descendants, geodesic_midpoints, refine, refine_levels
from .gmsh_backend import gmsh_module
from .shapes import BACKENDS, annulus_sector, disk, polygon, resolve_backend, rounded_rectangle, star
from .generator_kinds import GENERATORS, GeneratorKind, generator_kind, register_generator

__all__ = ["Mesh", "frames_from", "chain_order", "LOCAL_EDGES", "rectangle", "cylinder_arch",
           "cylinder_panel", "annulus", "hemisphere_quarter", "cross", "from_meshio", "read_meshio",
           "refine", "refine_levels", "carry_nodes", "carry_held", "descendants", "geodesic_midpoints",
           "star", "polygon", "rounded_rectangle", "disk", "annulus_sector", "gmsh_module",
           "BACKENDS", "resolve_backend", "GENERATORS", "GeneratorKind", "generator_kind", "register_generator"]
