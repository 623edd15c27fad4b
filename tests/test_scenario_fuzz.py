"""Property: random malformed scenario files never produce a traceback from inside the solver.

Whatever the text, ``scenario.loads`` either returns a validated Scenario or raises
ScenarioError; a scenario that validates then solves (one coarse step) or fails with a
CoreSE3Error (ConvergenceError, ...), never with an unrelated exception.
"""
import copy

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from core_se3 import scenario
from core_se3.errors import CoreSE3Error, ScenarioError

BASE = {
    "name": "fuzz",
    "units": "SI",
    "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 3, "ny": 1},
    "regions": {"end": {"box": {"x": [5.0, 10.0]}}},
    "material": {"E": 1.2e6, "nu": 0.3, "h": 0.1, "rho": 1.0, "regions": {"end": {"E": 2.4e6, "h": 0.12}}},
    "supports": [{"type": "clamp", "edge": "x0"},
                 {"type": "rotate", "edge": "x1", "axis": [1.0, 0.0, 0.0], "angle": 0.1,
                  "free": ["x"]}],
    "loads": [{"type": "edge_force", "edge": "x1", "force": [0.01, 0.0, 0.1], "scale": "linear"},   # x: free
              {"type": "pressure", "p": 0.05, "region": "end", "follower": True},
              {"type": "gravity", "g": [0.0, 0.0, -0.981]},
              {"type": "nodal", "nodes": [1], "moment": [0.0, 0.1, 0.0],
               "scale": [[0.0, 0.0], [1.0, 1.0]]}],
    "fields": {"coil": {"type": "gradient", "B": [0.0, 0.0, 1e-4],
                        "G": [[1e-5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1e-5]]}},
    "magnets": [{"Br": [0.1, 0.0, 0.0], "region": "end"}],
    "probes": [{"name": "tip", "edge": "x1"}],
    "solver": {"steps": 1, "max_iter": 8, "max_cutbacks": 2},
    "output": {"vtu": False},
}

scalars = st.one_of(
    st.none(), st.booleans(), st.integers(), st.integers(-3, 12),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -1.0, 0.5, 1e300, -1e-300]),
    st.text(max_size=8), st.sampled_from(["x0", "x1", "y0", "end", "clamp", "linear", "rectangle"]))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=3)), max_leaves=8)


def _paths(d, prefix=()):
    """Every (container, key) location in a nested dict/list document."""
    out = []
    items = d.items() if isinstance(d, dict) else enumerate(d)
    for k, x in items:
        out.append(prefix + (k,))
        if isinstance(x, (dict, list)):
            out.extend(_paths(x, prefix + (k,)))
    return out


PATHS = _paths(BASE)


def _strip_none(x):
    if isinstance(x, dict):
        return {str(k): _strip_none(v) for k, v in x.items() if v is not None}
    if isinstance(x, list):
        return [_strip_none(v) for v in x if v is not None]
    return x


@st.composite
def mutated_docs(draw):
    doc = copy.deepcopy(BASE)
    for _ in range(draw(st.integers(1, 3))):
        path = draw(st.sampled_from(PATHS))
        parent = doc
        try:
            for k in path[:-1]:
                parent = parent[k]
            key = path[-1]
            op = draw(st.sampled_from(["replace", "delete", "add"]))
            if op == "replace":
                parent[key] = draw(values)
            elif op == "delete":
                del parent[key]
            elif isinstance(parent, dict):
                parent[draw(st.text(min_size=1, max_size=6))] = draw(values)
            else:
                parent.append(draw(values))
        except (KeyError, IndexError, TypeError, AttributeError):
            pass                                      # an earlier mutation removed the path (or made it None)
    return _strip_none(doc)


def _check(text):
    try:
        scn = scenario.loads(text, file="fuzz.toml")
    except ScenarioError as exc:
        assert str(exc).startswith("fuzz.toml: "), str(exc)
        return "invalid"
    if scn.mesh.n_elements > 40:
        return "valid (not solved: too big for a fuzz test)"
    try:
        with np.errstate(all="ignore"):
            scn.problem.solve(steps=1, lam_end=scn.solver["lam_end"], max_iter=6, max_cutbacks=1)
    except CoreSE3Error:
        return "solver error"
    return "solved"


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_docs())
def test_malformed_documents_give_scenario_errors(doc):
    try:
        text = scenario.dumps(doc)
    except TypeError:
        return
    event(_check(text))


@settings(max_examples=80, deadline=None)
@given(st.data())
def test_garbled_text_gives_scenario_errors(data):
    text = scenario.dumps(BASE)
    for _ in range(data.draw(st.integers(1, 3))):
        i = data.draw(st.integers(0, len(text)))
        j = data.draw(st.integers(i, min(len(text), i + 20)))
        ins = data.draw(st.one_of(st.just(""), st.text(max_size=6),
                                  st.sampled_from(["nan", "-1", "[", "]", "=", '"', "\n", "0.5", "[[loads]]\n"])))
        text = text[:i] + ins + text[j:]
    event(_check(text))


def test_base_document_is_valid_and_solves():
    assert _check(scenario.dumps(BASE)) == "solved"
