"""The problems that tests/test_parallel.py solves serially and on two ranks (shared by the
test and tests/parallel_driver.py)."""
import numpy as np

from core_se3 import Material, Problem, mesh
from core_se3.catalogue.case import case_params, get_case
from core_se3.catalogue.run import build_problem

# name -> load steps; sze-hemisphere in load control (the catalogue traces it by arc length,
# which the distributed solver does not do; its path has no limit point up to P = 400)
CASES = {"sze-hemisphere": 10, "magnetic-gripper": 20, "plate-100x100": 1,
         # contact: a cantilever propped by a plane under its tip, the magnetic gripper closing
         # on a sphere (augmented Lagrangian: Uzawa updates, step caps, every rank's nodes)
         "contact-propped": 10, "magnetic-gripper-grasp": 20}
# the checks of accepted steps (issue 29, docs/STEPS.md): the snap check of contact steps on a
# tip force that jumps at load factor 0.5 with an obstacle (probed, then reported as a snap)
CASES["jumping-cantilever"] = 4
# contact face samples: a ball smaller than an element pushed into the middle of a face (nodal
# sampling lets it through; each rank carries the faces of its elements, their other nodes too)
CASES["contact-faces"] = 4
# the refine check: fuzz problem 158 (tests/test_step_checks.py) in one step, whose try 0 -> 0.25
# of 11 iterations onto another equilibrium is refused by its 4 parts (their end 0.12 ell off)
CASES["fuzz-158-1"] = 1
# the end check, inertia_check and the stability check: the sandwich strip of docs/EXTENDING.md recipe 6 to 0.2 C w
# stops at its even crossings (name -> steps, solve keywords)
STOPS = {"sandwich-1": (1, {}), "sandwich-2": (2, {}), "sandwich-5": (5, {}), "sandwich-10": (10, {}),
         "sandwich-inertia-1": (1, dict(inertia_check=True)), "sandwich-inertia-5": (5, dict(inertia_check=True)),
         "sandwich-sign-5": (5, dict(end_check=False))}       # det K's sign alone: the crossing at 0.533
# the midpoint probe: fuzz problem 144 (tests/test_step_checks.py) in one step, whose long try over
# a limit point is refused by the probe (name -> steps, solve keywords)
PROBES = {"fuzz-144-1": (1, {})}
# loads on one rank's nodes only, at the tip of a 12 x 1 strip (name -> steps, solve keywords): a
# uniform field turning by 1 rad a step (MAX_LOAD_TURN pi/4: two tries a step) on a magnet, which
# every rank splits as serially; a follower force (not conservative) with inertia_check, which
# every rank leaves uncounted as serially
ONE_SIDED = {"magnet-turning-tip": (2, {}), "follower-tip-inertia": (2, dict(inertia_check=True))}
# failures with the serial message (name -> steps, solve keywords): a roller rising under a plate
# (contact: no limit-point hint, which would send the user to arc length); a roller pressing into
# the clamped edge x1, which the rank that does not write holds (the cause named: that node)
FAILS = {"roller-lift": (4, dict(max_cutbacks=4)), "press-held": (2, dict(max_cutbacks=2))}
# designs optimised on two ranks (equilibria and sensitivities distributed) against serially
DESIGNS = ("design-tip-angle", "design-field-direction")


def build(name):
    """(Problem, steps, solve keywords) of a case."""
    if name == "plate-100x100":
        prob = Problem(mesh.rectangle(1.0, 1.0, 100, 100), Material(1e6, 0.3, 0.01))
        prob.clamp("x0")
        prob.add_pressure(0.5, follower=True)
        prob.add_probe("tip", "x1")
        return prob, CASES[name], {}
    if name == "magnet-turning-tip":
        from core_se3.model import UniformField
        from core_se3.model.fields import rotating_direction
        prob = Problem(mesh.rectangle(10.0, 1.0, 12, 1), Material(1e4, 0.3, 0.1))
        prob.clamp("x0")
        turn = rotating_direction((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), turns_per_unit=2.0 / (2 * np.pi))
        field = UniformField((0.0, 0.0, 0.05), scale=lambda lam: 1.0, direction=turn)
        prob.add_magnetic((1.0, 0.0, 0.0), field, elements=np.arange(10, 12), mu0=1.0)
        prob.add_probe("tip", "x1")
        return prob, *ONE_SIDED[name]
    if name == "press-held":
        prob = Problem(mesh.rectangle(2.0, 1.0, 8, 4), Material(1e4, 0.3, 0.02))
        prob.clamp("x1")
        prob.add_obstacle("cylinder", point=(2.0, 0.0, -0.07), axis=(0.0, 1.0, 0.0), radius=0.05,
                          motion=dict(translate=(0.0, 0.0, 0.2)), name="roller")
        prob.add_probe("tip", "x0")
        return prob, *FAILS[name]
    if name in FAILS:
        prob = Problem(mesh.rectangle(2.0, 1.0, 8, 4), Material(1e4, 0.3, 0.02, rho=1.0))
        prob.clamp("x0")
        prob.add_gravity(g=(0.0, 0.0, -0.5))
        prob.add_obstacle("cylinder", point=(1.5, 0.0, -0.06), axis=(0.0, 1.0, 0.0), radius=0.05,
                          motion=dict(translate=(0.0, 0.0, 0.3)), name="roller")
        prob.add_probe("tip", "x1")
        return prob, *FAILS[name]
    if name == "follower-tip-inertia":
        prob = Problem(mesh.rectangle(10.0, 1.0, 12, 1), Material(1e4, 0.3, 0.1))
        prob.clamp("x0")
        prob.add_edge_force("x1", (0.0, 0.0, 0.05), follower=True)
        prob.add_probe("tip", "x1")
        return prob, *ONE_SIDED[name]
    if name == "contact-faces":
        prob = Problem(mesh.rectangle(2.0, 1.0, 4, 2), Material(1e4, 0.0, 0.02))
        prob.clamp("x0")
        prob.add_obstacle("sphere", centre=(1.25, 0.25, -0.07), radius=0.05, motion=dict(translate=(0, 0, 0.1)),
                          name="pin")
        prob.add_probe("tip", "x1")
        return prob, CASES[name], {}
    if name == "jumping-cantilever":
        from test_contact_snap import _jumping_cantilever
        return _jumping_cantilever(), CASES[name], {}
    if name == "fuzz-158-1":
        from test_step_checks import _ANNULUS_158, _fuzz_problem
        return _fuzz_problem(_ANNULUS_158), CASES[name], {}
    if name in PROBES:
        from test_step_checks import _fuzz_strip_144
        return _fuzz_strip_144(), *PROBES[name]
    if name in STOPS or name == "sandwich-stable":
        from test_step_checks import _sandwich_strip
        steps, kw = STOPS.get(name, (2, {}))
        return _sandwich_strip(0.005 if name == "sandwich-stable" else 0.2), steps, kw
    case = get_case(name)
    return build_problem(case, case_params(case)), CASES[name], {}


def scenario_dict():
    """A small scenario with a clamp, an edge force, a gravity load and a probe, 4 steps."""
    return {"name": "par", "units": "consistent",
            "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 24, "ny": 4},
            "material": {"E": 1.2e6, "nu": 0.3, "h": 0.1, "rho": 1.0},
            "supports": [{"type": "clamp", "edge": "x0"}],
            "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 2.0]},
                      {"type": "gravity", "g": [0.0, 0.0, -1.0]}],
            "probes": [{"name": "tip", "edge": "x1"}],
            "solver": {"steps": 4},
            "output": {"vtu": True, "plots": False, "picture": False}}


def roof_on_symmetry_planes(follower=False):
    """The Scordelis-Lo roof 4x4 under its self-weight, held on its symmetry planes (the held
    nodes' tangent blocks carry their reactions' skew part, solvers.stability.asymmetry); with
    ``follower`` also a follower edge force (not conservative)."""
    import warnings
    from core_se3 import scenario
    from core_se3.catalogue import shell_course as sc
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prob = scenario.from_dict(sc.scenario_doc("scordelis-lo", 4, 0.25)).problem
    if follower:
        prob.add_edge_force("x1", (0.0, 0.0, -1e5), follower=True)
    return prob
