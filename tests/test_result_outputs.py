"""The numbers a run publishes, checked against exact solutions and against each other: sweep
rows (warm and cold), ..."""
import numpy as np
import pytest

from core_se3 import scenario

pytestmark = pytest.mark.core

E, H, L, W = 1.2e6, 0.1, 10.0, 1.0
M_PI = np.pi * E * W * H ** 3 / 12 / L          # the end moment that rolls the strip's tip by pi


def _strip(moment, steps):
    return scenario.from_dict({"mesh": {"generator": "rectangle", "L": L, "width": W, "nx": 8, "ny": 1},
                               "material": {"E": E, "nu": 0.0, "h": H},
                               "supports": [{"type": "clamp", "edge": "x0"}],
                               "loads": [{"type": "edge_moment", "edge": "x1", "moment": [0.0, -moment, 0.0]}],
                               "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": steps}})


def test_a_warm_sweep_row_keeps_the_turns_of_a_roll_up(tmp_path):
    """Pure bending, nu = 0: the tip turns by M L / (E I) exactly, 1.2 pi and 1.3 pi.  The warm
    row (one Newton solve from the 1.2 pi state) read 0.7 pi = 2 pi - 1.3 pi before: its probe
    rotation was unwrapped from zero, the cold row's along its load steps."""
    grid = {"loads[0].moment[1]": [-1.2 * M_PI, -1.3 * M_PI]}
    scn = _strip(1.2 * M_PI, 12)
    warm = scenario.sweep(scn, grid, out=str(tmp_path / "warm"), plot=False).rows
    cold = scenario.sweep(scn, grid, out=str(tmp_path / "cold"), plot=False, warm=False).rows
    assert [r["warm"] for r in warm] == [False, True] and not any(r["warm"] for r in cold)
    for rows in (warm, cold):
        assert [r["tip.rotation"] for r in rows] == [pytest.approx(1.2 * np.pi, rel=1e-9),
                                                      pytest.approx(1.3 * np.pi, rel=1e-9)]
        np.testing.assert_allclose(rows[1]["tip.rotation_vector"], [0.0, -1.3 * np.pi, 0.0], atol=1e-9)


def test_a_solve_continued_from_a_step_keeps_its_probes_turns():
    """Pure bending (exact): rolled to 1.2 pi, then continued to 1.3 pi from the stored step
    (``g_init=StepResult``): 1.2 pi and 1.3 pi, as one solve to 1.3 pi reads; bare frames still
    start from the angle modulo 2 pi (0.8 pi and 0.7 pi, said in the docstring).  Before, a
    StepResult was refused with a bare TypeError (float() of a StepResult)."""
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(L, W, 8, 1), Material(E, 0.0, H))
    p.clamp("x0")
    p.add_edge_moment("x1", (0.0, -M_PI, 0.0))
    p.add_probe("tip")
    first = p.solve(steps=12, lam_end=1.2).final
    on = p.solve(steps=1, lam_start=1.2, lam_end=1.3, g_init=first)
    assert [s.probes["tip"]["rotation_angle"] / np.pi for s in on.steps] == [pytest.approx(1.2, rel=1e-9),
                                                                             pytest.approx(1.3, rel=1e-9)]
    np.testing.assert_allclose(on.final.probes["tip"]["rotation_vector"], [0.0, -1.3 * np.pi, 0.0], atol=1e-9)


def _distorted(nx, ny, Lx, Wy, amp=0.2, seed=1):
    """A rectangle's interior nodes moved at random in the plane (boundary straight)."""
    from core_se3 import mesh
    from core_se3.mesh.core import Mesh
    m = mesh.rectangle(Lx, Wy, nx, ny)
    g0, X = m.g0.copy(), m.X
    inner = ((X[:, 0] > 1e-9) & (X[:, 0] < Lx - 1e-9) & (X[:, 1] > X[:, 1].min() + 1e-9)
             & (X[:, 1] < X[:, 1].max() - 1e-9))
    g0[inner, :2, 3] += amp * np.random.default_rng(seed).uniform(-1, 1, (inner.sum(), 2)) * [Lx / nx, Wy / ny]
    return Mesh(g0, m.quads, m.edges, None, m.regions)


@pytest.mark.parametrize("distorted", [False, True])
def test_resultants_of_uniform_tension_and_pure_bending_are_exact(distorted):
    """The VTU cell fields against exact solutions, on rectangles and a distorted mesh (interior
    nodes moved by up to 0.2 of an element): uniform tension sigma (nu = 0.3, free to contract)
    N1 = (sigma h, 0, 0), N2 = 0, M = 0; an end moment M (nu = 0) M1 = (0, M/w, 0), N = 0 --
    to round-off (measured 3e-12 and 4e-15 relative)."""
    from core_se3 import Material, Problem, mesh
    m = _distorted(4, 3, 2.0, 1.0) if distorted else mesh.rectangle(2.0, 1.0, 4, 3)
    sig, h = 100.0, 0.01
    p = Problem(m, Material(1e6, 0.3, h))
    at_x0 = lambda X: np.isclose(X[:, 0], 0.0)                          # noqa: E731
    corner = lambda X: at_x0(X) & np.isclose(X[:, 1], X[:, 1].min())   # noqa: E731
    p.fix(corner, [0, 1, 2, 3, 4, 5])
    p.fix(lambda X: at_x0(X) & ~corner(X), [0, 2, 3, 4, 5])
    p.fix(lambda X: ~at_x0(X), [2, 3, 4, 5])
    p.add_edge_force("x1", (sig * h * 1.0, 0.0, 0.0))
    cf = p.element.cell_fields(p.solve(steps=1).final.g)
    assert np.abs(cf["N1"] - [sig * h, 0.0, 0.0]).max() < 1e-10 * sig * h
    assert np.abs(cf["N2"]).max() < 1e-10 * sig * h
    assert np.abs(cf["M1"]).max() < 1e-12 and np.abs(cf["M2"]).max() < 1e-12
    m = _distorted(8, 3, 4.0, 1.0) if distorted else mesh.rectangle(4.0, 1.0, 8, 3)
    p = Problem(m, Material(1e6, 0.0, 0.05))
    p.clamp("x0")
    p.add_edge_moment("x1", (0.0, 1e-3, 0.0))
    cf = p.element.cell_fields(p.solve(steps=1).final.g)
    assert np.abs(cf["M1"] - [0.0, 1e-3, 0.0]).max() < 1e-10 * 1e-3
    # N of the bent state: the Newton tolerance's (3e-11), against the force scale M / h = 0.02
    assert np.abs(cf["N1"]).max() < 1e-7 * 1e-3 / 0.05 and np.abs(cf["M2"]).max() < 1e-10 * 1e-3


def test_a_cantilevers_resultants_are_its_load_and_arm():
    """Linear analysis (the VTU's linear strains, ``increments``) and nonlinear at a small load
    (tip deflection 3.3e-3 L): N1 = (0, 0, P/w) and M1 = (0, -(L - x) P/w, 0) at the element
    centres x, to 1e-9 linear and 1e-6 nonlinear (measured 2.2e-7: the turned elements' centre
    values; the moment arm shortens by O(deflection^2 / L)); the reactions -P and the moment of
    the load about the origin."""
    from core_se3 import Material, Problem, mesh
    from core_se3.solvers.linear import linear_increments
    m = mesh.rectangle(L, W, 16, 2)
    P = 1e-3
    p = Problem(m, Material(E, 0.0, H))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, P))
    xc = m.X[m.quads].mean(1)[:, 0]
    lin = p.solve_linear().final
    for st, eta, tol in ((lin, linear_increments(m.g0, lin.g), 1e-9), (p.solve(steps=1).final, None, 1e-6)):
        cf = p.element.cell_fields(st.g, eta)
        assert np.abs(cf["N1"] - [0.0, 0.0, P / W]).max() < tol * P / W
        assert np.abs(cf["M1"] - np.c_[0 * xc, -(L - xc) * P / W, 0 * xc]).max() < tol * P * L / W
        np.testing.assert_allclose(st.reaction_force, [0.0, 0.0, -P], atol=1e-8 * P)      # Newton's 4e-12
        np.testing.assert_allclose(st.reaction_moment, [0.0, P * L, 0.0], rtol=1e-6, atol=1e-8 * P * L)


def test_a_curved_panels_moment_is_the_end_moment_at_large_rotation():
    """A cylinder panel (R 2, 1.2 rad, 12 x 3) clamped at one straight edge, an end moment about
    its axis turning the other by 0.6 rad: M1 is the lab vector (0, M/w, 0) in every element and
    N = 0, to round-off: the lab frame of the output is right however far the elements turned."""
    from core_se3 import Material, Problem, mesh
    m = mesh.cylinder_panel(2.0, 1.0, -0.6, 0.6, 12, 3)
    mat = Material(1e5, 0.0, 0.05)
    M = 0.6 * mat.E * mat.h ** 3 / 12 / 1.2          # turns the free edge by ~0.6 rad
    p = Problem(m, mat)
    p.clamp("x0")
    p.add_edge_moment("x1", (0.0, M, 0.0))
    cf = p.element.cell_fields(p.solve(steps=4).final.g)
    assert np.abs(cf["M1"] - [0.0, M, 0.0]).max() < 1e-10 * M
    assert np.abs(cf["N1"]).max() < 1e-9 * M


def test_a_probe_on_a_closed_loop_is_refused():
    """The rim of a quad (its 4 nodes, a closed loop of element edges) has no midpoint: the probe
    sat at (2, 0, 0) for the ids [0, 1, 3, 2] and at (1, 0.5, 0) for the same nodes listed as
    [1, 3, 2, 0]; a tube's end ring likewise.  Now refused, naming the probe and the way out."""
    from core_se3 import Material, Problem
    from core_se3.errors import OptionError, ScenarioError
    from core_se3.mesh.core import Mesh, frames_from
    for ids in ([0, 1, 3, 2], [1, 3, 2, 0]):
        with pytest.raises(ScenarioError, match=r"probes\[0\]\.nodes.*closed loop.*nodes = \[ID\]"):
            scenario.from_dict({"mesh": {"generator": "rectangle", "L": 2.0, "width": 1.0, "nx": 1, "ny": 1},
                                "material": {"E": 1e4, "nu": 0.3, "h": 0.05},
                                "supports": [{"type": "clamp", "nodes": [0, 2]}],
                                "probes": [{"name": "rim", "nodes": ids}]})
    t = 2 * np.pi * np.arange(8) / 8                              # a tube, 8 around, 2 along
    X = np.array([[np.sin(a), y, np.cos(a)] for y in (0.0, 1.0, 2.0) for a in t])
    d1 = np.array([[np.cos(a), 0.0, -np.sin(a)] for _ in range(3) for a in t])
    quads = [[8 * j + i, 8 * j + (i + 1) % 8, 8 * (j + 1) + (i + 1) % 8, 8 * (j + 1) + i]
             for j in range(2) for i in range(8)]
    m = Mesh(frames_from(X, d1, np.cross(d1, [0.0, 1.0, 0.0])), np.array(quads), {"end": 16 + np.arange(8)})
    p = Problem(m, Material(1e4, 0.3, 0.05))
    with pytest.raises(OptionError, match="probe 'end': its 8 nodes form a closed loop"):
        p.add_probe("end", "end")
    p.add_probe("arc", m.edges["end"][:5])                        # an open part of it: its middle node
    assert p.probes["arc"].node_a == p.probes["arc"].node_b == 18


def test_a_linear_runs_vtu_shows_the_magnetic_loads_it_solved(tmp_path):
    """A linear analysis takes its loads at the reference: a magnet's couple h/mu0 B^r x B^a.
    Its VTU evaluated them at the linear state instead (B^r turned with the tip's 0.6 rad): the
    couple's y component read down to 82 % of the solved one (17.8 % off), with an x component.
    Now the point fields of the loads are those at the reference, whose integral is
    results.json's applied moment."""
    import glob
    import json
    import meshio
    B, Br, h, mu0 = 2e-4, 0.1, 0.5, 4e-7 * np.pi * 1e6
    scn = scenario.from_dict({"units": "N-mm-MPa", "mesh": {"generator": "rectangle", "L": 40.0, "width": 5.0,
                                                            "nx": 8, "ny": 1},
                              "material": {"E": 1.0, "nu": 0.3, "h": h}, "supports": [{"type": "clamp", "edge": "x0"}],
                              "magnets": [{"Br": [Br, 0.0, 0.0]}],
                              "fields": {"coil": {"type": "uniform", "B": [0.0, 0.0, B]}},
                              "probes": [{"name": "tip", "edge": "x1"}], "solver": {"control": "linear"},
                              "output": {"plots": False, "picture": False}})
    scenario.run(scn, out=str(tmp_path))
    st = json.load(open(tmp_path / "results.json"))["steps"][-1]
    assert 0.5 < st["probes"]["tip"]["rotation_angle"] < 0.7
    v = meshio.read(sorted(glob.glob(str(tmp_path / "vtu" / "step_*.vtu")))[-1])
    couple = -h / mu0 * Br * B                                      # (B^r x B^a)_y per unit area
    np.testing.assert_allclose(v.point_data["magnetic_couple"], np.tile([0.0, couple, 0.0], (18, 1)),
                               rtol=1e-12, atol=1e-12 * abs(couple))
    np.testing.assert_allclose(st["applied"]["moment"], [0.0, couple * 40.0 * 5.0, 0.0], rtol=1e-12,
                               atol=1e-12 * abs(couple))


@pytest.mark.parametrize("text, found", [("[1, 2]", "an array (a list)"), ("3.5", "a number"), ('"r.json"', "a string"),
                                          ("null", "null"), ("{bad", "not JSON")])
def test_read_json_names_the_file_of_a_document_that_is_not_an_object(tmp_path, text, found):
    """A result file whose top level is a list, a number, a string or null failed with a bare
    AttributeError ('list' object has no attribute 'get'), and text that is not JSON with a
    JSONDecodeError that did not name the file: now a ResultFileError (a ValueError) naming the
    file, what it holds and what was expected."""
    from core_se3.errors import ResultFileError
    from core_se3.results import read_json, write_json, result_document
    path = tmp_path / "result.json"
    path.write_text(text)
    with pytest.raises(ResultFileError, match="core-se3-result") as info:
        read_json(path)
    assert info.value.file == str(path) and str(path) in str(info.value) and found in str(info.value)
    assert isinstance(info.value, ValueError)
    write_json(path, result_document("demo", "core_se3", "default", {}, {"nx": None}, [], {}))
    assert read_json(path)["case"] == "demo"


def test_each_step_reports_its_largest_newton_correction(tmp_path, capsys):
    """The step table and results.json showed only each step's residual; the size of its Newton
    corrections (computed for the step checks, kept only in the solver's log) was not shown.  Now
    ``max_correction`` (|eta|_s / ell) per step and a 'correction' column: for the first step from
    the reference it is the first correction, K0^-1 f: the linear analysis' increments at the same
    load factor (0.42641, equal to 1e-9); '-' at the start."""
    import json

    from core_se3 import cli
    from core_se3.solvers.convergence import increment_norm
    from core_se3.solvers.linear import linear_increments
    doc = {"name": "cantilever", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
           "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}], "solver": {"steps": 3},
           "output": {"vtu": False, "plots": False, "picture": False}}
    path = tmp_path / "c.toml"
    path.write_text(scenario.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "o")]) == 0
    steps = json.loads((tmp_path / "o" / "results.json").read_text())["steps"]
    p = scenario.load(path).problem
    lin = p.solve(control="linear", lam_end=1.0 / 3.0).final.g
    first = increment_norm(linear_increments(p.mesh.g0, lin), p.length_scale)
    assert steps[0]["max_correction"] is None
    assert abs(steps[1]["max_correction"] - first) <= 1e-9 * first and 0.3 < first < 0.5, (steps[1], first)
    assert all(0.0 < s["max_correction"] < 1.0 for s in steps[1:])
    lines = capsys.readouterr().out.splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.lstrip().startswith("step"))
    assert lines[head].split()[-1] == "correction"
    shown = [ln.split()[-1] for ln in lines[head + 1:head + 5]]
    assert shown[0] == "-" and [float(x) for x in shown[1:]] == [float(f"{s['max_correction']:.2e}") for s in steps[1:]]


def test_each_step_reports_the_force_and_moment_parts_of_its_residual(tmp_path, capsys):
    """The step table, results.json and StepResult gave only the relative residual, which mixes
    forces and moments / ell over a force scale; an FE user asks for the force [N] and moment
    [N mm] residuals apart.  Now ``residual_force`` / ``residual_moment``: the norms of the parts
    of r = r_int - f_ext on the free dofs, from the forces the step records.  Checked against
    the equations evaluated anew at each stored state, and against the relative residual,
    which they make up: sqrt(|r_F|^2 + (|r_M| / ell)^2) / scale, to round-off; a linear
    analysis' are those of its linear system (K eta = f to round-off)."""
    import json

    from core_se3 import cli
    from core_se3.solvers.convergence import scaled_norm
    doc = {"name": "cantilever", "units": "N-mm-MPa",
           "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 6, "ny": 2},
           "material": {"E": 1.2e3, "nu": 0.3, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]},
                     {"type": "edge_moment", "edge": "x1", "moment": [0.0, 5e-4, 0.0]}],
           "solver": {"steps": 3, "rtol": 1e-6}, "output": {"vtu": False, "plots": False, "picture": False}}
    path = tmp_path / "c.toml"
    path.write_text(scenario.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "o")]) == 0
    steps = json.loads((tmp_path / "o" / "results.json").read_text())["steps"]
    p = scenario.load(path).problem
    res = p.solve(steps=3, rtol=1e-6)
    ell = p.length_scale
    for st, rec in zip(res.steps[1:], steps[1:]):
        ev = p.evaluate(st.g, st.load_factor, tangent=False)
        r = np.reshape(p.assembler().scatter(ev.r), (-1, 6))           # the free dofs, as the solver sees them
        F, M = np.linalg.norm(r[:, :3]), np.linalg.norm(r[:, 3:])
        assert st.residual_force == pytest.approx(F, rel=1e-12) and st.residual_moment == pytest.approx(M, rel=1e-12)
        assert (rec["residual_force"], rec["residual_moment"]) == pytest.approx((F, M), rel=1e-6)
        scale = max(scaled_norm(ev.f_ext, ell), scaled_norm(ev.r_int, ell))
        assert np.hypot(F, M / ell) / scale == pytest.approx(st.residual_history[-1], rel=1e-10)
        assert 0.0 < F and 0.0 < M and st.residual_history[-1] < 1e-6       # a real residual, converged
    lines = capsys.readouterr().out.splitlines()
    head = next(ln for ln in lines if ln.lstrip().startswith("step"))
    assert "residual    |r_F| [N] |r_M| [N mm] correction" in head, head
    lin = p.solve(control="linear").final           # K eta = f solved to round-off: eps cond(K) |f|, cond ~ 1e6
    assert 0.0 < lin.residual_force < 1e-8 * 1e-3 and 0.0 < lin.residual_moment < 1e-8 * 1e-3 * 10


def test_a_step_or_a_probe_a_result_does_not_have_is_named():
    """Result.displacements(5) of a 3-step result was a bare IndexError (1.5: a TypeError), and
    step.probes['tpi'] a bare KeyError: now an OptionError naming the steps, and an
    UnknownProbeError (an OptionError and a KeyError) naming the closest probe."""
    from core_se3 import Material, Problem, mesh
    from core_se3.errors import OptionError
    p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0))
    p.add_probe("tip", "x1")
    r = p.solve(steps=2)
    for k in (5, -10, 1.5):
        with pytest.raises(OptionError, match=r"is not stored: the result has 3 steps"):
            r.displacements(k)
    with pytest.raises(KeyError, match=r"no probe 'tpi'; did you mean 'tip'\?"):
        r.final.probes["tpi"]
    with pytest.raises(OptionError):
        r.final.probes["tpi"]
    assert r.displacements(-1).shape == (10, 3) and r.final.probes.get("tpi") is None


def test_result_documents_are_strict_json_with_their_non_finite_numbers_named(tmp_path):
    """write_json and io.write_json_atomic (results.json) wrote a NaN or an infinity as the
    bare words NaN / Infinity: not JSON, refused by strict readers (JSON.parse, jq, Go, serde).
    They are null now, named by their JSON pointer under 'non_finite'; read_json puts them back."""
    import json
    from core_se3 import io
    from core_se3.results import SCHEMA, VERSION, read_json, write_json

    def strict(path):
        def refuse(word):
            raise ValueError(f"{word} is not JSON")
        return json.loads(open(path).read(), parse_constant=refuse)

    doc = dict(schema=SCHEMA, version=VERSION, steps=[dict(probes={"a/b": {"u": [1.0, float("nan"), 2.0]}})],
               balance_error=float("inf"))
    for path, writer in ((tmp_path / "r.json", write_json), (tmp_path / "a.json", io.write_json_atomic)):
        writer(path, doc)
        text = strict(path)
        assert text["steps"][0]["probes"]["a/b"]["u"] == [1.0, None, 2.0] and text["balance_error"] is None
        assert text["non_finite"] == {"/steps/0/probes/a~1b/u/1": "NaN", "/balance_error": "Infinity"}
        back = read_json(path)
        assert np.isnan(back["steps"][0]["probes"]["a/b"]["u"][1]) and back["balance_error"] == np.inf
        assert "non_finite" not in back and back["steps"][0]["probes"]["a/b"]["u"][::2] == [1.0, 2.0]
    assert "non_finite" not in strict(write_json(tmp_path / "f.json", dict(doc, balance_error=0.0, steps=[]))
                                      or tmp_path / "f.json")
