"""core_se3: geometrically exact Cosserat shells on SE(3)."""
from . import se3, mesh, fields
from .errors import (ConvergenceError, CoreSE3Error, ElementTooDistortedError, LoadError,
                     MaterialError, MeshError, ScenarioError, SingularSystemError, SupportError)
from .material import Material
from .problem import Problem

__all__ = ["se3", "mesh", "fields", "Material", "Problem", "CoreSE3Error", "ConvergenceError",
           "SingularSystemError", "MaterialError", "MeshError", "LoadError", "SupportError",
           "ElementTooDistortedError", "ScenarioError"]
__version__ = "0.1.0"
