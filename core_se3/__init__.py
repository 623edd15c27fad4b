"""core_se3: geometrically exact Cosserat shells on SE(3).

Every node of the mid-surface carries a frame g = (R, phi) in SE(3); strains are left-trivialised
twists; the 4-node quad is solved by Newton with exponential updates g <- g exp(eta).  The
package is a stack of layers that import only downward (docs/ARCHITECTURE.md):

    lie -> mesh -> fem -> assembly -> model -> results -> solvers -> parallel -> io -> design -> scenario -> control
    -> catalogue -> cli

Example (a strip rolled into a full circle by an end moment M = 2 pi EI / L)
-------
>>> import numpy as np
>>> import core_se3 as cs
>>> p = cs.Problem(cs.mesh.rectangle(10.0, 1.0, 10, 1), cs.Material(E=1.2e7, nu=0.0, h=0.1))
>>> p.clamp("x0"); p.add_probe("tip", "x1")
>>> p.add_edge_moment("x1", (0.0, -2 * np.pi * 1.2e7 * 0.1 ** 3 / 12 / 10.0, 0.0))
>>> tip = p.solve(steps=40).final.probes["tip"]
>>> (tip["u"].round(9) + 0.0).tolist(), round(float(np.linalg.norm(tip["rotation_vector"])), 9)     # back at the clamp
([-10.0, 0.0, 0.0], 6.283185307)
"""
from . import lie, mesh
from . import fem, model, results, solvers  # noqa: F401  (solvers registers Problem.solve's controls)
from . import parallel  # noqa: F401  (registers the distributed solver; imports no MPI)
from .errors import (CheckpointError, ConvergenceError, CoreSE3Error, ElementTooDistortedError, LoadError,
                     MaterialError, MeshError, OptionError, ScenarioError, SingularSystemError, SupportError)
from .fem import Element, Material, RegionMaterial, register_element
from .model import (Field, Load, LoadKind, Param, Problem, register_field, register_load)
from .model import fields
from .results import Result, StepResult
from .solvers import (ArcLengthOptions, NewtonOptions, arc_length, displacement_control,
                      newton_solve)

# The upper layers a solve does not need are imported at their first use (PEP 562): a
# one-shot `core-se3 bench run` does not pay for the design, scenario (TOML) and output
# (XML) modules it never touches.  ``core_se3.io``, ``core_se3.design``, ``core_se3.scenario``,
# ``core_se3.control``, ``core_se3.catalogue``, ``Scenario`` and ``load_scenario`` behave as
# eagerly imported names.
_LAZY = {"io": ("io", None), "design": ("design", None), "scenario": ("scenario", None), "control": ("control", None),
         "catalogue": ("catalogue", None), "Scenario": ("scenario", "Scenario"),
         "load_scenario": ("scenario", "load")}


def __getattr__(name):
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'core_se3' has no attribute {name!r}") from None
    import importlib
    obj = importlib.import_module(f"{__name__}.{module}")
    return obj if attr is None else getattr(obj, attr)


def __dir__():
    return sorted(set(globals()) | set(_LAZY))

__all__ = ["lie", "mesh", "fem", "model", "fields", "results", "solvers", "io", "design", "scenario", "control",
           "catalogue",
           "Problem", "Material", "RegionMaterial", "Result", "StepResult", "Scenario", "load_scenario",
           "newton_solve", "arc_length", "displacement_control", "NewtonOptions", "ArcLengthOptions",
           "Element", "Load", "LoadKind", "Param", "Field", "register_element", "register_load",
           "register_field", "CoreSE3Error", "ConvergenceError", "SingularSystemError", "MaterialError",
           "MeshError", "LoadError", "SupportError", "ElementTooDistortedError", "ScenarioError",
           "CheckpointError", "OptionError"]
__version__ = "0.2.0"
