"""The contract of every registered kind (core_se3/scenario/contracts.py), read from its
declaration alone: a TOML round trip, a clear error for each required key missing, and for the
kinds that carry a residual the tangent against central differences at a large rotation and
frame invariance.  A new kind is tested by registering it: the built-in registries here, the
recipes' plugin kinds of docs/EXTENDING.md in a fresh interpreter; and docs/SCENARIOS.md shows
the vocabulary's own tables."""
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import core_se3 as cs
from core_se3.design.kinds import TARGETS, VARIABLES
from core_se3.fem import ELEMENTS, MATERIALS
from core_se3.mesh import GENERATORS
from core_se3.model import FIELDS, LOADS, OBSTACLES, SUPPORTS
from core_se3.registry import Section, registries
from core_se3.scenario import contracts
from core_se3.scenario.schema import update_doc

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REGISTRY = dict(generator=GENERATORS, material=MATERIALS, supports=SUPPORTS, loads=LOADS, fields=FIELDS,
                obstacles=OBSTACLES, variables=VARIABLES, targets=TARGETS)
KINDS = [(s, n) for s, reg in REGISTRY.items() for n in reg] + [("elements", n) for n in ELEMENTS]


def _kind(section, name):
    return Section(name) if section == "elements" else REGISTRY[section][name]


def test_every_registry_is_walked():
    """Negative control: the walk covers every registry of Kinds and every element."""
    assert {r.what for r in registries()} <= {reg.what for reg in REGISTRY.values()}
    assert len(KINDS) >= 35 and ("obstacles", "box") in KINDS and ("elements", "seed") in KINDS


@pytest.mark.parametrize("section,name", KINDS, ids=[f"{s}:{n}" for s, n in KINDS])
def test_toml_round_trip(section, name):
    assert contracts.round_trip(section, _kind(section, name)) == 0.0


@pytest.mark.parametrize("section,name", KINDS, ids=[f"{s}:{n}" for s, n in KINDS])
def test_each_required_key_missing_is_named(section, name):
    kind = _kind(section, name)
    assert contracts.missing_keys(section, kind) == list(kind.required())


PHYSICAL = [(s, n) if s != "elements" or not ELEMENTS[n].stateful else
            pytest.param(s, n, marks=pytest.mark.skip(reason="a stateful element (the seed's scheme): its residual "
                                                                "is not a function of the frames"))
            for s, n in KINDS if s in contracts.PHYSICAL and s != "generator"]
IDS = [f"{s}:{n}" for s, n in KINDS if s in contracts.PHYSICAL and s != "generator"]


@pytest.mark.parametrize("section,name", PHYSICAL, ids=IDS)
def test_tangent_at_a_large_rotation(section, name):
    assert contracts.fd_tangent(section, _kind(section, name)) < 1e-6


@pytest.mark.parametrize("section,name", PHYSICAL, ids=IDS)
def test_frame_invariance(section, name):
    assert contracts.frame_invariance(section, _kind(section, name)) < 1e-10


def test_the_contracts_can_fail():
    """Negative controls: a load without its load stiffness, and one whose force does not turn
    with the scene (declared frame=None), each caught by its contract."""
    from core_se3.model import LoadEvaluation, LoadKind, Param
    from core_se3.model.loads import NodalLoad

    class NoStiffness(NodalLoad):             # a dead lab force with its load stiffness dropped
        def evaluate(self, g, lam, tangent=True):
            return LoadEvaluation(super().evaluate(g, lam, tangent).f)

        def compiled(self, pattern):          # (the numba kernel of NodalLoad has the stiffness)
            return None
    kinds = [LoadKind("no_stiffness", "nodes", (Param("force", "vector"),),
                      lambda problem, nodes, scale, force: NoStiffness(problem.mesh.n_nodes, nodes, np.ones(len(nodes)),
                                                                       force=force, scale=scale)),
             LoadKind("fixed_z", "nodes", (Param("force", "vector", frame=None),),
                      lambda problem, nodes, scale, force: NodalLoad(problem.mesh.n_nodes, nodes, np.ones(len(nodes)),
                                                                     force=force, scale=scale))]
    try:
        for k in kinds:
            LOADS.add(k)
        with pytest.raises(AssertionError, match="tangent against central differences"):
            contracts.fd_tangent("loads", kinds[0])
        with pytest.raises(AssertionError, match="rigid rotation"):
            contracts.frame_invariance("loads", kinds[1])
        assert contracts.fd_tangent("loads", kinds[1]) < 1e-6 and contracts.frame_invariance("loads", LOADS["nodal"]) < 1e-10
    finally:
        for k in kinds:
            LOADS.pop(k.name, None)


def test_tangent_check_steps_below_the_contact_band():
    """A correct contact tangent at a converged state with the default band (1e-6 h = 1e-8):
    central differences of step 1e-6 cross the kinks of the force law (0.16 measured);
    tangent_fd_check's default step, a tenth of the band, sees the derivative."""
    from core_se3.model import verify
    p = cs.Problem(cs.mesh.rectangle(1.0, 0.1, 10, 1), cs.Material(1e4, 0.0, 0.01), backend="numpy")
    p.clamp("x0")
    p.add_pressure(-0.02)
    p.add_obstacle("half_space", point=(0, 0, -0.01), normal=(0, 0, 1))
    g = p.solve(steps=4, predictor="tangent").final.g
    assert verify.fd_step(p) == 1e-9
    assert verify.tangent_fd_check(p, g, 1.0, h=1e-6)[0] > 0.05            # the old default step
    assert verify.tangent_fd_check(p, g, 1.0)[0] < 1e-6


def test_the_schema_document_shows_the_vocabulary():
    path = os.path.join(ROOT, "docs", "SCENARIOS.md")
    text = open(path, encoding="utf-8").read()
    assert text.count("<!-- schema: ") >= 12
    assert update_doc(text) == text, "docs/SCENARIOS.md: run python scripts/schema_tables.py"


RECIPE_CONTRACTS = """
import sys
from core_se3.scenario.contracts import check_kind
from core_se3.scenario.plugins import load_plugins
from core_se3.design.kinds import VARIABLES
from core_se3.fem import MATERIALS
from core_se3.model import OBSTACLES, SUPPORTS
load_plugins(sys.argv[1:])
for section, kind in [("obstacles", OBSTACLES["torus"]), ("material", MATERIALS["sandwich"]),
                      ("supports", SUPPORTS["symmetry"]), ("variables", VARIABLES["couple"])]:
    print(section, kind.name, check_kind(section, kind))
"""


def test_the_recipes_kinds_pass_the_contracts(tmp_path):
    """The plugin kinds of recipes 5-8, registered in a fresh interpreter, pass the same contracts."""
    text = open(os.path.join(ROOT, "docs", "EXTENDING.md"), encoding="utf-8").read()
    files = []
    for i in range(5, 9):
        body = re.split(r"^## Recipe \d+[^\n]*\n", text, flags=re.M)[i]
        code = "\n".join(re.findall(r"```python\n(.*?)```", body, flags=re.S))
        files.append(tmp_path / f"recipe{i}.py")
        files[-1].write_text(code)
    r = subprocess.run([sys.executable, "-c", RECIPE_CONTRACTS, *map(str, files)], capture_output=True, text=True,
                       cwd=tmp_path, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.count("fd_tangent") == 3, r.stdout


WITHOUT_TOMLLIB = """
import importlib, sys
try:                                       # 3.11+: tomllib stands in for the backport pyproject installs on 3.10
    sys.modules.setdefault("tomli", importlib.import_module("tomllib"))
except ModuleNotFoundError:                # Python 3.10: tomli itself
    pass
sys.modules["tomllib"] = None              # Python 3.10 has no tomllib
from core_se3.model import LOADS
from core_se3.scenario.contracts import check_kind
print(sorted(check_kind("loads", LOADS["edge_force"])))
"""


def test_check_kind_runs_on_python_3_10_without_tomllib():
    """pyproject supports Python >= 3.10 (tomli there, as scenario.spec reads it); the contracts'
    round trip imported tomllib itself, so a plugin author's ``check_kind`` on 3.10 stopped with
    "ModuleNotFoundError: No module named 'tomllib'"."""
    r = subprocess.run([sys.executable, "-c", WITHOUT_TOMLLIB], capture_output=True, text=True, cwd=ROOT,
                       env=dict(os.environ, PYTHONPATH=ROOT), timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "round_trip" in r.stdout and "frame_invariance" in r.stdout
