"""core_se3: geometrically exact Cosserat shells on SE(3)."""
from . import se3, mesh
from .errors import (ConvergenceError, CoreSE3Error, ElementTooDistortedError, LoadError,
                     MaterialError, MeshError, SingularSystemError, SupportError)
from .material import Material
from .problem import Problem

__all__ = ["se3", "mesh", "Material", "Problem", "CoreSE3Error", "ConvergenceError",
           "SingularSystemError", "MaterialError", "MeshError", "LoadError", "SupportError",
           "ElementTooDistortedError"]
__version__ = "0.1.0"
