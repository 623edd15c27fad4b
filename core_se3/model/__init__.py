"""Layer 4, the model: loads (an extension point with a registry), applied fields (another),
magnetic materials, supports, probes and the :class:`Problem` that owns the discrete equations.

Example
-------
>>> from core_se3 import model
>>> sorted(model.FIELDS), sorted(model.OBSTACLES)
(['dipole', 'gradient', 'uniform'], ['box', 'cylinder', 'half_space', 'sphere'])
"""
from .base import (LOADS, REQUIRED, Load, LoadEvaluation, LoadKind, Param, ScaleTable, load_kind, overrides,
                   register_load)
from .fields import (FIELDS, MU0, DipoleField, Field, FieldKind, GradientField, Superposition,
                     UniformField, UserField, check_field, field_kind, register_field,
                     rotating_direction)
from .loads import NodalLoad, SurfaceLoad, edge_weights, line_shares
from .magnetics import MagneticLoad, Magnetisation
from .obstacles import (OBSTACLES, Obstacle, ObstacleKind, check_sdf, make_obstacle, obstacle_kind,
                        register_obstacle, rigid_motion, rotation, translation)
from .obstacle_kinds import Box, Cylinder, HalfSpace, Sphere, UserSDF
from .contact import ContactLaw, ContactLoad, add_obstacle
from .probes import Probe
from .problem import SOLVERS, Evaluation, Problem
from .supports import LabSpring, LabTiltSpring, Prescribed, RotationComponentSpring
from .support_kinds import SUPPORTS, SupportKind, register_support, support_kind
from .verify import tangent_fd_check, zero_modes

__all__ = ["Load", "LoadEvaluation", "LoadKind", "Param", "ScaleTable", "REQUIRED", "LOADS", "register_load",
           "load_kind", "Field", "FieldKind", "FIELDS", "register_field", "field_kind", "MU0",
           "UniformField", "GradientField", "DipoleField", "UserField", "Superposition",
           "check_field", "rotating_direction", "NodalLoad", "SurfaceLoad", "edge_weights", "line_shares",
           "Magnetisation", "MagneticLoad", "Probe", "Problem", "Evaluation", "SOLVERS",
           "Prescribed", "LabSpring", "LabTiltSpring", "RotationComponentSpring",
           "tangent_fd_check", "zero_modes", "overrides", "Obstacle", "ObstacleKind", "OBSTACLES",
           "register_obstacle", "obstacle_kind", "make_obstacle", "rigid_motion", "translation", "rotation",
           "check_sdf", "HalfSpace", "Sphere", "Cylinder", "Box", "UserSDF", "ContactLaw", "ContactLoad", "add_obstacle",
           "SUPPORTS", "SupportKind", "register_support", "support_kind"]
