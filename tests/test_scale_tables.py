"""Load stepping through the points of a scale table (``[[loads]] scale = [[lam, s], ...]``,
``core_se3.model.ScaleTable``; docs/STEPS.md, 'Bounded splitting').

A requested step from one side of a table's peak to the other went between two states at the
same load without ever applying the peak: the hinged roof of examples/snap-roof.toml (quarter
8x8, limit point at P/3000 = 0.7435) under a load taken to 1.0 and back to 0 ended 'complete' on
the unloaded roof in 3 load steps, where 20 steps stop at the limit point.  Now every try ends on
the table points inside its step."""
import pathlib
import re
import warnings

import numpy as np
import pytest

from core_se3 import scenario
from core_se3.errors import ConvergenceError
from core_se3.solvers import newton_solve

ROOF = pathlib.Path(__file__).resolve().parents[1] / "examples" / "snap-roof.toml"


def _roof(peak, steps):
    """The snap roof under load control, its crown load's scale 0 -> peak (at 0.5) -> 0 (at 1)."""
    text = ROOF.read_text()
    head = text[:text.index("[solver]")]
    head = head.replace("force = [0.0, 0.0, -750.0]", f"force = [0.0, 0.0, -750.0]\nscale = [[0.0, 0.0], [0.5, {peak}], [1.0, 0.0]]")
    return scenario.loads(head + f'[solver]\ncontrol = "load"\nsteps = {steps}\n\n[output]\npicture = false\n',
                          base_dir=str(ROOF.parent))


@pytest.mark.parametrize("steps", [1, 3])
def test_a_step_across_a_tables_peak_past_the_limit_point_stops_there(steps):
    """The peak (P/3000 = 1) lies beyond the limit point (0.7435, at load factor 0.37177 on the
    way up): 1 and 3 steps (whose requested load factors never reach the peak) stop there as 20
    steps do (last converged 0.371753), naming the limit point.  Before, both exited complete on
    the unloaded roof (every requested load factor's state is that of its load, but the path to it
    passes the limit point; and the file was warned about, its load's scale 'is 0 at every load
    factor of the run: it acts nowhere')."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        prob = _roof(1.0, steps).problem
    with pytest.raises(ConvergenceError, match="limit point") as err:
        newton_solve(prob, steps=steps)
    last = float(re.search(r"the last converged load factor is ([0-9.e+-]+)", str(err.value)).group(1))
    assert 0.37177 - 2.5e-4 < last <= 0.37177      # within the cut-backs' floor, 2^-12 of the step
    assert max(abs(e["lam"] - 0.5) for e in err.value.result.log) > 0.1      # not a try past the peak


def test_below_the_limit_point_the_roof_returns_through_the_peak():
    """Peak 0.6 of P_max (below the limit point): 1 step lands a try on the peak (load factor
    0.5) and returns to the unloaded roof (a conservative elastic shell); its state at the peak
    is that of 2 steps to the crown deflection's 1e-9."""
    one = newton_solve(_roof(0.6, 1).problem, steps=1, record_substeps=True)
    two = newton_solve(_roof(0.6, 2).problem, steps=2)
    at_peak = [s for s in one.steps if abs(s.load_factor - 0.5) < 1e-14]
    assert at_peak, [s.load_factor for s in one.steps]
    w_one, w_two = at_peak[0].probes["crown"]["u"][2], two.steps[1].probes["crown"]["u"][2]
    assert w_two < -5.0 and abs(w_one - w_two) < 1e-9 * abs(w_two)
    assert abs(one.final.probes["crown"]["u"][2]) < 1e-9 * abs(w_two)


def test_scale_table():
    """ScaleTable: linear between its points, constant outside, its points as knots; bad tables
    refused."""
    from core_se3.model import ScaleTable
    s = ScaleTable([[0.0, 0.0], [0.5, 1.0], [1.0, -1.0]])
    assert s(0.25) == 0.5 and s(0.75) == 0.0 and s(-1.0) == 0.0 and s(3.0) == -1.0
    assert s.knots == (0.0, 0.5, 1.0)
    for bad in ([[0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]], [[0.0, np.nan], [1.0, 1.0]]):
        with pytest.raises(Exception, match="scale table"):
            ScaleTable(bad)


def _arc_roof(table):
    """The snap roof of examples/snap-roof.toml (arc length) with its crown load's scale ``table``."""
    text = ROOF.read_text().replace("force = [0.0, 0.0, -750.0]", f"force = [0.0, 0.0, -750.0]\nscale = {table}")
    return scenario.loads(text, file="roof.toml", base_dir=str(ROOF.parent))


@pytest.mark.parametrize("table, bend", [("[[0.0, 0.0], [0.5, 0.6], [1.0, 0.0]]", 0.5),
                                         ("[[0.0, 0.0], [0.3, 0.6], [1.0, 1.0]]", 0.3)])
def test_arc_length_refuses_a_bent_scale_table_naming_its_key(table, bend):
    """Arc length takes the load factor as the path's parameter: at a table's bend q = d f_ext /
    d lam jumps (at a peak it is 0).  The snap roof under a peak at 0.5 failed there 'at lam
    0.500015 ... the load factor may have turned twice within the step', and under a table bent
    at 0.3 with 'load 'nodal': its scale(lam) is nan at load factor nan'.  Now the file is refused
    naming the key, and so is the Python API's (ShellSystem); a straight table is accepted."""
    from core_se3.errors import OptionError, ScenarioError
    from core_se3.solvers import arc_length
    with pytest.raises(ScenarioError, match=rf"loads\[0\]\.scale.*bends at load factor {bend:g}"):
        _arc_roof(table)
    prob = _roof(0.6, 1).problem if bend == 0.5 else _arc_roof("[[0.0, 0.0], [1.0, 1.0]]").problem
    if bend == 0.5:
        with pytest.raises(OptionError, match="bends at load factor 0.5"):
            arc_length(prob, lam_end=0.2)
    else:
        assert arc_length(prob, lam_end=0.2).steps[-1].load_factor == pytest.approx(0.2, abs=1e-12)


def test_the_limit_point_hint_is_not_given_for_a_table_that_starts_at_zero():
    """limit_point_hint (the 'Probable cause' of a load-stepping failure) compared q . K^-1 q at
    the start and at the last state with q a backward difference: at 0 a table's q is that of
    its constant part below its first point, 0, so S_p = 0 and every failure under a table from
    (0, 0) was called a limit point.  The unloaded strip (S_p = 1 with the linear scale, no
    hint) now gets none with the table [[0, 0], [1, 1]] (the same programme) either."""
    from core_se3 import Material, Problem, mesh
    from core_se3.scenario import make_scale
    from core_se3.solvers.stability import limit_point_hint
    for scale in (None, make_scale([[0.0, 0.0], [1.0, 1.0]]), make_scale([[0.0, 0.0], [0.5, 2.0], [1.0, 3.0]])):
        p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
        p.clamp("x0")
        p.add_edge_force("x1", (0.0, 0.0, 1.0), scale=scale)
        assert limit_point_hint(p, p.mesh.g0, 0.75) is None


def _roof_scaled(scale):
    """The snap roof under load control with its crown load's scale a Python callable."""
    prob = _roof(1.0, 1).problem
    ld = next(ld for ld in prob.loads if getattr(ld, "scale", None) is not None and hasattr(ld.scale, "knots"))
    ld.scale = scale
    prob.scale_tables.clear()
    prob.note_scale(scale)
    return prob


@pytest.mark.parametrize("steps", [1, 3])
def test_a_step_across_a_python_callables_peak_past_the_limit_point_stops_there(steps):
    """A scale given in Python as a callable, s(lam) = sin(pi lam) (peak 1 = P/3000 at 0.5, past
    the limit point 0.7435 at lam = asin(0.7435) / pi = 0.2662): 1 and 3 steps stop at the limit
    point, as 20 steps do.  Before, the callable's peak was not known and both exited 'complete' on
    the unloaded roof (1 step: lam 0 -> 1, s 0 -> 0)."""
    import math
    prob = _roof_scaled(lambda lam: math.sin(math.pi * lam))
    assert prob.untabled_scales and not prob.scale_knots
    with pytest.raises(ConvergenceError, match="limit point") as err:
        newton_solve(prob, steps=steps)
    last = float(re.search(r"the last converged load factor is ([0-9.e+-]+)", str(err.value)).group(1))
    limit = math.asin(0.74354) / math.pi          # 0.7435 of the table's test, on the sine's way up
    assert limit - 2.5e-4 < last <= limit + 1e-4


def test_a_callable_added_with_its_load_is_stepped_onto():
    """``Problem.add(load)`` notes the load's scale as the ``add_*`` methods do: a ScaleTable's
    points and a callable's turns are landed on (before, a load built by hand and added kept its
    table unseen: the same roof ended 'complete' in 1 step)."""
    from core_se3.model import ScaleTable
    prob = _roof(1.0, 1).problem
    ld = next(ld for ld in prob.loads if hasattr(getattr(ld, "scale", None), "knots"))
    prob.loads.remove(ld)
    prob.scale_tables.clear()
    prob.add(ld)
    assert prob.scale_knots == (0.0, 0.5, 1.0) and isinstance(ld.scale, ScaleTable)
    with pytest.raises(ConvergenceError, match="limit point"):
        newton_solve(prob, steps=1)
