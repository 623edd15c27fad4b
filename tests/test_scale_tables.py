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
