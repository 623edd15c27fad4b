"""Layer 2, the finite-element layer: quadrature, the material law, the elements (an extension
point with a registry) and stress resultants.

Example
-------
>>> from core_se3 import fem, mesh, Material
>>> el = fem.make_element("default", mesh.rectangle(1.0, 0.2, 4, 1), Material(1e3, 0.0, 0.01))
>>> type(el).__name__, float(el.evaluate(el.mesh.g0, tangent=False).energy)
('DefaultElement', 0.0)
"""
from .element import ELEMENTS, Element, ElementEvaluation, make_element, register_element
from .element_default import MAX_EDGE_ANGLE, DefaultElement, edge_twists, tying_matrices
from .element_seed import SeedElement
from .material import Material, RegionMaterial, ResultantLaw, law_matrix, strain_operators
from .material_kinds import MATERIALS, MaterialKind, material_kind, register_material
from .quadrature import GAUSS_2x2, shape_functions, surface_jacobian
from .resultants import element_resultants

__all__ = ["Element", "ElementEvaluation", "ELEMENTS", "register_element", "make_element",
           "DefaultElement", "SeedElement", "edge_twists", "tying_matrices", "MAX_EDGE_ANGLE",
           "Material", "RegionMaterial", "ResultantLaw", "law_matrix", "strain_operators", "GAUSS_2x2",
           "shape_functions", "surface_jacobian", "element_resultants", "MATERIALS", "MaterialKind",
           "register_material", "material_kind"]
