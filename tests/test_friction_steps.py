"""The friction check of load stepping (``solvers.friction_probe``, docs/STEPS.md "The friction
check"): a frictional run's states do not depend on the requested steps (issue 29's step table).

``friction-pushed-cantilever`` (40x1, the end pressed on a wall that then slides: the end sticks,
then slips at s*) in 1 step of its slide ended 7.3e-5 of its path's scale from its 36-step state
(``benchmarks/results/robustness.md``, main at 75c4f65), converged and silent.  Measured: the
difference is the cone's hardening, not the slip history's integration -- a slipping node's
friction is mu p (1 + d k |s| / mu p) with |s| the slip over the *last* step, so the stored
state depends on that step's size (6.5e-4 of mu p in 1 step, 5.8e-4 in 36: the 36-step
reference was off too); the halves of the one step that holds the stick-slip transition agree
with it to 4.9e-9.
"""
import numpy as np
import pytest

from core_se3.catalogue import run_case

SCALE = 0.027354            # the pushed cantilever's largest displacement (its path's scale)


def _run(steps, **kw):
    _, res, prob = run_case("friction-pushed-cantilever", steps=steps, **kw)
    return res


def _distance(a, b):
    return float(np.abs(a.steps[-1].g[:, :3, 3] - b.steps[-1].g[:, :3, 3]).max()) / SCALE


@pytest.fixture(scope="module")
def ref36():
    return _run(36)


def test_one_step_of_the_slide_agrees_with_36_steps(ref36):
    """1 and 36 steps of the slide agree to 1e-6 of the path's scale (measured 7.7e-9); without
    the check they differ by 7.3e-5 (main's table cell), and the excess of the slipping end's
    friction over the cone is at most friction_tol (measured 9.8e-8; 6.5e-4 without)."""
    one = _run(1)
    assert _distance(one, ref36) <= 1e-6
    assert one.steps[-1].checks["friction_excess"] <= 1e-7
    assert one.steps[-1].checks["friction_relaxations"] >= 1
    off1, off36 = _run(1, friction_check=False), _run(36, friction_check=False)
    assert _distance(off1, off36) > 5e-5                       # main: 7.26e-5
    assert "friction_probes" not in off1.steps[-1].checks


def test_the_stick_slip_step_is_probed_and_refined_to_a_tight_tolerance(ref36):
    """The step in which the end starts to slip is solved again in halves (1 probe at the
    default tolerance: its halves agree to 4.9e-9); with friction_tol 1e-10 the halves miss
    the bound and the step is refined (go back, quarter steps), and the state still agrees."""
    one = _run(1, friction_halving=True)
    assert one.steps[-1].checks["friction_probes"] >= 1
    assert one.steps[-1].checks["friction_error"] <= 1e-7
    assert _run(1).steps[-1].checks["friction_probes"] == 0          # friction_halving is off by default
    tight = _run(1, friction_tol=1e-10, friction_halving=True)
    chk = tight.steps[-1].checks
    assert chk["friction_refinements"] >= 1 and chk["friction_unresolved"] == 0
    assert chk["friction_error"] <= 1e-10
    assert _distance(tight, ref36) <= 1e-6


def test_a_step_where_everything_sticks_is_not_probed():
    """The ramp of P (load factor 0.1 -> 0.2: the end sticks throughout) costs nothing: no
    probe, no relaxation, the same tries as without the check."""
    on, off = _run(1, friction_halving=True), _run(1, friction_check=False)
    st_on, st_off = on.steps[2], off.steps[2]
    assert st_on.load_factor == pytest.approx(0.2)
    assert st_on.checks["friction_probes"] == 0 and st_on.checks["friction_relaxations"] == 0
    assert st_on.attempts == st_off.attempts
    np.testing.assert_array_equal(st_on.g, st_off.g)


def test_the_friction_keys_are_solver_options():
    from core_se3.errors import OptionError
    from core_se3.solvers.options import NewtonOptions
    opts = NewtonOptions()
    assert opts.friction_check is True and opts.friction_tol == 1e-7
    with pytest.raises(OptionError):
        NewtonOptions(friction_tol=0.0)


def test_the_relaxations_keep_the_slip_of_the_step():
    """The friction check solves the slid state again at its load factor (33 relaxations in the
    1-step slide); the reported largest slip is the step's (the relaxations add up), as without
    the check: main reported the last relaxation's alone, 1.6e-7 for the step's 1.711e-3 (then
    the last of its 16 sub-steps; now the step's whole slip: the wall's travel less the end's
    final deflection, in either run -- they end 1.7e-5 apart, the hardening's error without the
    check)."""
    from core_se3.catalogue.cases_friction import PUSH_PARAMS, push_formula
    travel = push_formula(PUSH_PARAMS)["travel"]
    for kw in ({}, dict(friction_check=False)):
        end = _run(1, **kw).steps[-1]
        whole = travel - float(end.g[[40, 81], 2, 3].mean())
        assert whole > 1e-3 and abs(end.contact["wall"]["largest_slip"] / whole - 1) < 1e-9, kw


def test_the_largest_slip_of_a_step_is_its_whole_slip_however_it_was_split():
    """While the end slides, the wall moves travel / 9 = 6.0843e-3 a step (9 steps of the slide)
    and the end stays at s*: its slip over a step is the wall's motion.  The solver splits each
    such step in 4 (cut-backs), and ``largest_slip`` was the last part's: 1.521e-3; in 1 step of
    the slide (split in 16) 1.711e-3 for the end's whole slip, the travel less the end's final
    deflection, 2.74045e-2.  Now the slip counts from the last stored step (``close_step``)
    through every sub-step: both to 1e-9."""
    from core_se3.catalogue.cases_friction import PUSH_PARAMS, push_formula
    travel = push_formula(PUSH_PARAMS)["travel"]
    nine, one = _run(9), _run(1)
    for st in nine.steps[-4:]:
        assert st.attempts > 4 and abs(st.contact["wall"]["largest_slip"] / (travel / 9) - 1) < 1e-9, \
            st.contact["wall"]["largest_slip"]
    end = one.steps[-1]
    whole = travel - float(end.g[[40, 81], 2, 3].mean())
    assert abs(end.contact["wall"]["largest_slip"] / whole - 1) < 1e-9, (end.contact["wall"]["largest_slip"], whole)
