"""Layer 7b, design: sensitivities of a converged state (adjoint and direct methods on the
left-trivialised residual), the design variables (applied field, magnetisation per region, E
and h per region, load magnitudes), the quantities a design targets (positions, orientations,
angles, energy, user functions), the equilibria of a design (warm-started path following in the
variables) and the inverse solver (``Design``: several poses, bounds, regularisation, scipy
optimisers with adjoint gradients).  See docs/DESIGN.md.

Example
-------
>>> from core_se3 import design
>>> "sensitivity" in design.__all__ and "Design" in design.__all__
True
"""
from .equilibrium import ElementCheck, EquilibriumOptions, EquilibriumState, assign_all, follow, solve_flat
from .inverse import EQUILIBRIA, METHODS, Design, DesignResult, Pose, Smoothness, Target
from .objectives import (Energy, NodePosition, Orientation, ProbePosition, Quantity, RotationAngle,
                         UserQuantity, local_jacobian)
from .sensitivity import Sensitivity, SolveWith, quantity_jacobian, residual_derivative, sensitivity
from .magnetisation import Parametrisation, RegionMagnetisation
from .material import MaterialVariable
from .variables import FieldGradientVariable, FieldVariable, LoadMagnitude, Variable, magnetic_loads, polar_vector

__all__ = ["sensitivity", "Sensitivity", "SolveWith", "residual_derivative", "quantity_jacobian",
           "Variable", "FieldVariable", "FieldGradientVariable", "RegionMagnetisation", "Parametrisation", "MaterialVariable",
           "LoadMagnitude", "magnetic_loads", "polar_vector",
           "Quantity", "NodePosition", "ProbePosition", "Orientation", "RotationAngle", "Energy",
           "UserQuantity", "local_jacobian",
           "Design", "DesignResult", "Pose", "Target", "Smoothness", "METHODS", "EQUILIBRIA",
           "EquilibriumOptions", "EquilibriumState", "ElementCheck", "follow", "solve_flat", "assign_all"]
