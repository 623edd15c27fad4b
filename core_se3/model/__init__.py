"""Layer 4, the model: loads (an extension point with a registry), applied fields (another),
magnetic materials, supports, probes and the :class:`Problem` that owns the discrete equations.

Example
-------
>>> from core_se3 import model
>>> sorted(model.FIELDS)
['dipole', 'gradient', 'uniform']
"""
from .base import LOADS, REQUIRED, Load, LoadEvaluation, LoadKind, Param, load_kind, register_load
from .fields import (FIELDS, MU0, DipoleField, Field, FieldKind, GradientField, Superposition,
                     UniformField, UserField, check_field, field_kind, register_field,
                     rotating_direction)
from .loads import NodalLoad, SurfaceLoad, edge_weights
from .magnetics import MagneticLoad, Magnetisation
from .probes import Probe
from .problem import SOLVERS, Evaluation, Problem
from .supports import LabSpring, LabTiltSpring, Prescribed, RotationComponentSpring
from .verify import tangent_fd_check, zero_modes

__all__ = ["Load", "LoadEvaluation", "LoadKind", "Param", "REQUIRED", "LOADS", "register_load",
           "load_kind", "Field", "FieldKind", "FIELDS", "register_field", "field_kind", "MU0",
           "UniformField", "GradientField", "DipoleField", "UserField", "Superposition",
           "check_field", "rotating_direction", "NodalLoad", "SurfaceLoad", "edge_weights",
           "Magnetisation", "MagneticLoad", "Probe", "Problem", "Evaluation", "SOLVERS",
           "Prescribed", "LabSpring", "LabTiltSpring", "RotationComponentSpring",
           "tangent_fd_check", "zero_modes"]
