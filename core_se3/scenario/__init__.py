"""Layer 8, scenarios: TOML files describing a shell problem (schema and validation, building the
Problem through the registries, writing TOML) and the runner that solves them with output,
checkpoints and resume.

    scn = scenario.load("gripper.toml")      # parse + validate; raises ScenarioError(file, key)
    prob = scn.problem                       # the core_se3.Problem, supports checked
    res = scenario.run(scn, out="out/gripper")

Load-factor scaling: every load, prescribed rotation and field carries ``scale``: "linear"
(s = lam, the default), "constant" (s = 1), or a table [[lam0, s0], [lam1, s1], ...] (lam
strictly increasing; linear in between, constant outside).

Example
-------
>>> from core_se3 import scenario
>>> sorted(scenario.GENERATORS)
['annulus', 'annulus_sector', 'cylinder_arch', 'cylinder_panel', 'disk', 'hemisphere_quarter', 'polygon', 'rectangle', 'rounded_rectangle', 'star']
"""
from .geometry import GENERATORS, MAX_ELEMENTS
from .physics import ARCLENGTH_DEFAULTS, NON_PHYSICAL, OUTPUT_DEFAULTS, SOLVER_DEFAULTS, material_index
from .runner import RunInterrupted, RunResult, cell_fields, picture, plot_probes, point_fields, run
from .spec import TOP_KEYS, Scenario, from_dict, load, loads
from .sweep import SweepResult, check_sweep, sweep
from .mesh_check import MeshCheck, check_mesh, check_problem_mesh
from .units import UNIT_SYSTEMS
from .toml_writer import dumps
from .validate import make_scale

__all__ = ["Scenario", "load", "loads", "from_dict", "dumps", "make_scale", "run", "RunResult",
           "RunInterrupted", "GENERATORS", "TOP_KEYS", "SOLVER_DEFAULTS", "ARCLENGTH_DEFAULTS",
           "OUTPUT_DEFAULTS", "NON_PHYSICAL", "MAX_ELEMENTS", "material_index", "point_fields",
           "cell_fields", "picture", "plot_probes", "sweep", "check_sweep", "SweepResult", "UNIT_SYSTEMS", "check_mesh",
           "check_problem_mesh", "MeshCheck"]
