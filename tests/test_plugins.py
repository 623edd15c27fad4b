"""User kinds from files: a scenario's ``plugins = [...]`` and ``--plugin FILE`` import the user's
registrations before validation (core_se3/scenario/plugins.py); a kind's ValueError is named
by key; the one vocabulary refuses a malformed declaration where it is written."""
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from core_se3 import scenario
from core_se3.errors import ScenarioError
from core_se3.model import LOADS, LoadKind, Param
from core_se3.registry import Kind, Registry, Section, register
from core_se3.scenario.plugins import LOADED, load_plugins

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))

# a dead lab force on each selected node, its total given (an exact answer: a cantilever's end
# under an axial force F stretches by F L / (E h w))
PLUGIN = '''
import numpy as np
from core_se3.model import LoadKind, NodalLoad, Param, register_load


def _total(problem, nodes, scale, total):
    if not np.any(total):
        raise ValueError(f"total must not be zero, got {list(total)}")
    return NodalLoad(problem.mesh.n_nodes, nodes, np.full(len(nodes), 1.0 / len(nodes)), force=total, scale=scale)


register_load(LoadKind("{name}", "nodes", (Param("total", "vector"),), _total, doc="a total force shared by the nodes"))
'''
SCENARIO = '''
name = "stretch"
{plugins}
[mesh]
generator = "rectangle"
L = 2.0
width = 0.5
nx = 4
ny = 1
[material]
E = 1000.0
nu = 0.0
h = 0.1
[[supports]]
type = "clamp"
edge = "x0"
[[loads]]
type = "{name}"
edge = "x1"
total = [{F}, 0.0, 0.0]
[[probes]]
name = "tip"
edge = "x1"
[solver]
steps = 1
[output]
vtu = false
plots = false
picture = false
'''


@pytest.fixture(autouse=True)
def _registries_restored():
    """The kinds these tests register in this process are taken out again (the doctests list
    the built-in registries)."""
    from core_se3 import registry
    saved, loaded = [(r, dict(r)) for r in registry.registries()], dict(LOADED)
    by_kind, regs = dict(registry._BY_KIND), list(registry._REGISTRIES)
    yield
    for r, entries in saved:
        r.clear()
        r.update(entries)
    LOADED.clear()
    LOADED.update(loaded)
    registry._BY_KIND.clear()
    registry._BY_KIND.update(by_kind)
    registry._REGISTRIES[:] = regs


def _files(tmp_path, name, F=2.0, plugins=True):
    (tmp_path / "kinds.py").write_text(PLUGIN.replace("{name}", name))
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO.format(name=name, F=F, plugins='plugins = ["kinds.py"]' if plugins else ""))
    return path


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "core_se3", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, env=ENV, timeout=600)


def test_a_kind_from_a_plugin_file_runs_through_the_command_line(tmp_path):
    path = _files(tmp_path, "total_force")
    r = _cli("run", path, "--out", tmp_path / "out", "-q", cwd=tmp_path / "..")
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "out" / "results.json").read_text())
    u = doc["steps"][-1]["probes"]["tip"]["u"]
    # a uniform stretch: F L / (E h w) = 2 * 2 / (1000 * 0.1 * 0.5), exactly
    assert abs(u[0] / 0.08 - 1) < 1e-12 and abs(u[2]) < 1e-14


def test_plugin_from_the_command_line_and_without_it(tmp_path):
    path = _files(tmp_path, "total_force", plugins=False)
    r = _cli("run", path, "--check", cwd=tmp_path)
    assert r.returncode == 2 and "[loads[0].type]: unknown value 'total_force'" in r.stderr, r.stderr
    r = _cli("run", path, "--check", "--plugin", "kinds.py", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    r = _cli("kinds", "loads", "--plugin", "kinds.py", cwd=tmp_path)
    assert r.returncode == 0 and "total_force: edge or nodes, total, scale -- a total force shared by the nodes" in r.stdout
    r = _cli("run", path, "--check", "--plugin", "missing.py", cwd=tmp_path)
    assert r.returncode == 2 and "[--plugin[0]]: plugin file 'missing.py' does not exist" in r.stderr


def test_a_plugins_value_error_names_the_key(tmp_path):
    path = _files(tmp_path, "total_force_z", F=0.0)
    with pytest.raises(ScenarioError, match=r"\[loads\[0\]\.total\]: total_force_z: total must not be zero"):
        scenario.load(path)


def test_plugin_files_are_imported_once_and_fingerprinted(tmp_path):
    path = _files(tmp_path, "total_force_once")
    scn = scenario.load(path)
    again = scn.with_overrides({"solver.steps": 2})           # validated anew: no second registration
    assert again.fingerprint == scn.fingerprint and LOADED[str(tmp_path / "kinds.py")] in json.dumps(scn.physical)
    # another version of the plugin, in another process, makes another fingerprint (--resume refuses)
    code = "import sys; from core_se3 import scenario; print(scenario.load(sys.argv[1]).fingerprint)"
    fp = [subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, env=ENV).stdout]
    (tmp_path / "kinds.py").write_text(PLUGIN.replace("{name}", "total_force_once") + "\n# edited\n")
    fp.append(subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, env=ENV).stdout)
    assert fp[0].strip() == scn.fingerprint and fp[1].strip() and fp[1] != fp[0]


@pytest.mark.parametrize("body,message", [
    ("x = 1 +\n", "SyntaxError at line 1"),
    ("import numpy\nraise RuntimeError('no licence server')\n", "RuntimeError: no licence server (line 2: "),
    ("from core_se3.model import load_kind, register_load\nregister_load(load_kind('gravity'))\n",
     "ValueError: load kind 'gravity' is registered twice"),
])
def test_a_broken_plugin_is_named_with_its_line(tmp_path, body, message):
    (tmp_path / "bad.py").write_text(body)
    with pytest.raises(ScenarioError, match=r"\[plugins\[0\]\]: plugin 'bad.py' failed to import: ") as e:
        load_plugins(["bad.py"], str(tmp_path))
    assert message in str(e.value)


def test_a_plugin_module_by_name(tmp_path, monkeypatch):
    (tmp_path / "lab_kinds.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert load_plugins(["lab_kinds"])[0][0] == "lab_kinds"
    with pytest.raises(ScenarioError, match="plugin module 'no_such_lab_kinds' is not importable"):
        load_plugins(["no_such_lab_kinds"])


def test_a_malformed_declaration_is_refused_where_it_is_written():
    with pytest.raises(TypeError, match="unknown kind 'vektor'"):
        Param("x", "vektor")
    with pytest.raises(TypeError, match="key 'a' is declared twice"):
        Section("s", (Param("a", "number"), Param("a", "bool")))
    with pytest.raises(TypeError, match="key 'scale' is the section's own"):
        LOADS.add(LoadKind("scaled", "nodes", (Param("scale", "number"),), lambda *a: None))
    with pytest.raises(TypeError, match="target must be 'line', 'nodes' or 'elements'"):
        LoadKind("somewhere", "faces", (), lambda *a: None)
    with pytest.raises(TypeError, match="is not a kind of an extension point"):
        register(Section("x"))
    class Widget(Kind):
        pass
    reg = Registry("widget", Widget)
    with pytest.raises(TypeError, match="a widget must be a Widget, got str"):
        reg.add("w")



def test_every_register_function_is_the_registrys_add():
    """register_load/field/... check what Registry.add checks: a field kind declaring the
    section's own key 'scale' was accepted by register_field (it bypassed the reserved keys)."""
    from core_se3.model import FieldKind, register_field, register_load
    with pytest.raises(TypeError, match="key 'scale' is the section's own"):
        register_field(FieldKind("scaled", (Param("scale", "number"),), lambda *a: None))
    with pytest.raises(TypeError, match="a load kind must be a LoadKind, got str"):
        register_load("gravity")


def test_the_vocabulary_describes_every_section():
    """One description per section: the validator's allowed keys are the declared ones."""
    from core_se3.scenario.schema import OUTPUT, SECTIONS, SOLVER
    assert [s.name for s in SECTIONS][:2] == ["scenario", "edge"]
    doc = {"mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 1, "ny": 1},
           "material": {"E": 1.0, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}]}
    for section, kind in (("output", OUTPUT), ("solver", SOLVER)):
        with pytest.raises(ScenarioError) as e:
            scenario.from_dict(dict(doc, **{section: {"nonsense": 1}}))
        assert e.value.key == f"{section}.nonsense" and all(k in str(e.value) for k in kind.keys()[:3])
    # a default written out is read back (inf bounds of a design variable)
    assert np.isinf(Param("upper", "number", float("inf")).default)
