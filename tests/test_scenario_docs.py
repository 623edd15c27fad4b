"""Every example fragment of docs/SCENARIOS.md (```toml blocks starting with '# feature:')
validates and solves when merged into a small base scenario, so the schema document cannot
drift from the code."""
import copy
import os
import re
try:
    import tomllib
except ModuleNotFoundError:     # Python 3.10 (README: the core tests run on any Python >= 3.10)
    import tomli as tomllib
import warnings

import numpy as np
import pytest

from core_se3 import scenario
from core_se3.errors import ElementWarning, MeshWarning
from core_se3.scenario import runner

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "SCENARIOS.md")
BASE = {
    "name": "docs",
    "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1},
    "supports": [{"type": "clamp", "edge": "x0"}],
    "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 0.5]}],
}
ARRAYS = ("supports", "loads", "magnets", "probes")


def fragments():
    text = open(DOC).read()
    blocks = re.findall(r"```toml\n(.*?)```", text, flags=re.S)
    out = [(re.match(r"# feature: (.*)", b).group(1).strip(), b) for b in blocks if b.startswith("# feature:")]
    assert len(out) >= 12
    return out


def merged(fragment):
    doc = copy.deepcopy(BASE)
    for k, v in tomllib.loads(fragment).items():
        if k == "mesh" or k in ARRAYS or not isinstance(v, dict):
            doc[k] = v
        else:
            doc.setdefault(k, {}).update(v)
    return doc


@pytest.mark.parametrize("name,fragment", fragments(), ids=[n for n, _ in fragments()])
def test_documented_fragment_validates_and_solves(name, fragment, tmp_path):
    scn = scenario.from_dict(merged(fragment), file=f"SCENARIOS.md[{name}]",
                             base_dir=os.path.join(ROOT, "examples"))
    if name == "output":
        res = runner.run(scn, out=str(tmp_path / "o"))
        assert os.path.exists(res.files["picture"]) and "probes" not in res.files
        return
    if name == "arc length":
        res = runner.run(scn, out=str(tmp_path / "o"))
        assert res.doc["control"] == "arclength" and abs(res.doc["steps"][-1]["load_factor"] - 1.0) < 1e-12
        return
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        res = scn.problem.solve(steps=2, lam_end=scn.solver["lam_end"])
    assert np.all(np.isfinite(res.final.g)) and res.final.balance_error < 1e-8
    # a documented mesh is one the element's and the mesh's own checks accept: the graded mesh's
    # fragment (a panel graded toward x1 but clamped at x0 alone) warned, phi^3 L / h = 2.31
    bad = [str(w.message)[:120] for w in said if issubclass(w.category, (ElementWarning, MeshWarning))]
    assert not bad, bad
