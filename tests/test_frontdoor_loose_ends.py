"""The front door's loose ends of the sixth review (what reaches a user through a scenario file or
the Python API and was said late, wrongly or not at all); each test fails on the code before its
fix.  (Series files: tests/test_io.py; result documents: tests/test_result_outputs.py; a Problem's
linear solver: tests/test_solver.py.)
"""
import copy
import warnings

import pytest

from core_se3 import scenario
from core_se3.errors import AngleWarning, ScenarioError

QUIET = {"vtu": False, "plots": False, "picture": False}
STRIP = {"name": "strip", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
         "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
         "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}],
         "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 1}, "output": dict(QUIET)}


def doc(**sections):
    d = copy.deepcopy(STRIP)
    d.update(copy.deepcopy(sections))
    return d


def load(d):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(d, file="s.toml")


def test_a_linear_solver_this_machine_lacks_is_named_at_its_key(monkeypatch):
    """[solver] linear_solver = "mumps" where petsc4py is missing (the NumPy 2 environment) was
    refused only when the solve began ('solver 'mumps' needs petsc4py'), after the set-up; the
    Problem now refuses it when made, and the scenario names [solver.linear_solver] (not
    [material], where the Problem's other refusals go) and the choices on this machine."""
    from core_se3.model.solving import LINEAR_SOLVERS
    monkeypatch.setitem(LINEAR_SOLVERS, "mumps", lambda: "needs petsc4py, not installed here")
    with pytest.raises(ScenarioError, match=r"\[solver.linear_solver\]: linear_solver 'mumps' needs petsc4py, not "
                                            r"installed here; the choices on this machine: auto, banded, superlu"):
        load(doc(solver={"steps": 1, "linear_solver": "mumps"}))


def _angle_warnings(fn):
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        fn()
    return [w for w in said if issubclass(w.category, AngleWarning)], said


@pytest.mark.parametrize("what", ["rotate_edge", "move_edge", "box", "star", "polygon", "sector", "motion", "field",
                                  "command"])
def test_an_angle_in_degrees_warns_in_the_python_api(what):
    """rotate_edge(angle=90) meant a quarter turn and rolled the edge 14.3 times, a box rotated
    by (0, 0, 90) or a star's angle0 = 45 landed at 90 rad and 45 rad -- silently, where a
    scenario file warned.  Every angle entering the Python API now gives one AngleWarning, said
    at the caller's line, the same value in radians (a turn, a half turn) nothing."""
    import numpy as np
    from core_se3 import Material, Problem, mesh
    from core_se3.model import obstacles
    from core_se3.model.fields import field_kind
    from core_se3.model.obstacle_kinds import Box

    def make(angle):
        p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
        calls = {"rotate_edge": lambda: p.rotate_edge("x1", (1.0, 0.0, 0.0), angle),
                 "move_edge": lambda: p.move_edge("x1", axis=(1.0, 0.0, 0.0), angle=angle),
                 "box": lambda: Box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), rotation=(0.0, 0.0, angle / 2)),
                 "star": lambda: mesh.star(4, 10.0, 2.0, size=2.0, backend="structured", angle0=angle / 2),
                 "polygon": lambda: mesh.polygon(5, 1.0, size=0.5, backend="structured", angle0=angle / 2),
                 "sector": lambda: mesh.annulus_sector(1.0, 2.0, 1.0, size=0.5, backend="structured",
                                                      theta0=angle / 2),
                 "motion": lambda: obstacles.rigid_motion(axis=(0.0, 0.0, 1.0), angle=angle),
                 "field": lambda: field_kind("uniform").build(
                     {"B": (0.0, 0.0, 1.0), "rotate": {"axis": (1.0, 0.0, 0.0), "angle": angle, "start": 0.0,
                                                       "end": 1.0}}, None, 1.0),
                 "command": lambda: _polar_session().update(B=[0.3, angle])}
        return calls[what]

    found, said = _angle_warnings(make(90.0))
    assert len(found) == 1 and found[0].filename == __file__, [str(w.message) for w in said]
    assert "in radians (90 degrees is 1.5708 rad)" in str(found[0].message) or \
        "in radians (45 degrees is 0.785398 rad)" in str(found[0].message)
    assert _angle_warnings(make(2 * np.pi))[0] == []


def _polar_session():
    from core_se3 import Material, Problem, mesh
    from core_se3.control import Session
    from core_se3.design import FieldVariable
    from core_se3.model import UniformField
    p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e3, 0.0, 0.05))
    p.clamp("x0")
    f = UniformField((0.0, 0.0, 1e-3))
    p.add_magnetic((1.0, 0.0, 0.0), f, mu0=1.0)
    return Session(p, 1.0, [FieldVariable(p, f, "polar", name="B")])


def test_a_scenario_angle_in_degrees_is_said_once_at_its_key():
    """The scenario's warning names the key; the layers below (now warning too) stay quiet."""
    d = doc(supports=[{"type": "clamp", "edge": "x0"},
                      {"type": "rotate", "edge": "x1", "axis": [1.0, 0.0, 0.0], "angle": 90.0, "free": ["x"]}],
            loads=[], probes=[])
    found, said = _angle_warnings(lambda: scenario.from_dict(d, file="s.toml"))
    assert found == [] and [str(w.message) for w in said if "[supports[1].angle]" in str(w.message)] != []


def test_a_sweeps_columns_have_their_units_in_sweep_json(tmp_path):
    """sweep.csv's columns (tip.uz, supports[0].Fz, ...) came without units, and sweep.json did not
    say them either (results.json does): with units = "N-mm-MPa" a reader could not tell mm
    from m.  sweep.json now holds the unit system and the unit of every computed column."""
    import json
    d = doc(units="N-mm-MPa", material={"E": 1.2e3, "nu": 0.0, "h": 0.1})
    res = scenario.sweep(load(d), {"loads[0].force[2]": [1e-3, 2e-3]}, out=str(tmp_path / "sw"), plot=False)
    st = json.load(open(tmp_path / "sw" / "sweep.json"))
    assert st["unit_system"]["name"] == "N-mm-MPa" and len(res.rows) == 2
    cu = st["column_units"]
    assert (cu["tip.uz"], cu["tip.rotation"], cu["supports[0].Fz"], cu["supports[0].My"]) == ("mm", "rad", "N", "N mm")
    assert "loads[0].force[2]" not in cu and "status" not in cu


def test_a_json_path_that_is_a_directory_is_called_one(tmp_path, capsys):
    """--json DIR (an existing directory) was refused as 'a file that is not an earlier bench
    run's JSON' (check-mesh: '... check's JSON: the check would overwrite it'): it is a directory,
    and the way on is a file's path in it."""
    from core_se3 import cli
    d = tmp_path / "results"
    d.mkdir()
    scn = tmp_path / "s.toml"
    scn.write_text(scenario.dumps(doc()))
    for args, name in ((["bench", "run", "cantilever-shear", "--json", str(d)], "case.json"),
                       (["check-mesh", str(scn), "--json", str(d)], "check.json")):
        assert cli.main(args) == 2
        err = capsys.readouterr().err
        assert f"--json {str(d)!r} is a directory: give the path of a file (e.g. {str(d / name)!r})" in err, err
    assert list(d.iterdir()) == []


def test_a_bench_json_that_cannot_be_written_keeps_the_earlier_one(tmp_path, capsys, monkeypatch):
    """bench run --json wrote in place: a disk that filled while it wrote left the earlier
    document of the same path cut short (not JSON).  Now it is written beside and moved into
    place, so the earlier one stays whole and the error says the solve's table is complete."""
    import builtins
    import errno
    import json
    from core_se3 import cli
    path = tmp_path / "case.json"
    assert cli.main(["bench", "run", "cantilever-shear", "--steps", "2", "-q", "--json", str(path)]) == 0
    before = path.read_text()
    real_open = builtins.open

    class Full:
        def __init__(self, fh):
            self.fh = fh

        def write(self, text):
            self.fh.write(text[:100])
            raise OSError(errno.ENOSPC, "No space left on device")

        def __getattr__(self, name):
            return getattr(self.fh, name)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

    def full_disk(file, mode="r", *args, **kw):
        fh = real_open(file, mode, *args, **kw)
        return Full(fh) if "w" in mode and str(tmp_path) in str(file) else fh
    monkeypatch.setattr(builtins, "open", full_disk)
    assert cli.main(["bench", "run", "cantilever-shear", "--steps", "2", "-q", "--json", str(path)]) != 0
    monkeypatch.undo()
    assert "No space left on device" in capsys.readouterr().err
    assert path.read_text() == before and json.loads(before)["case"] == "cantilever-shear"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.json"]          # no half-written temporary
