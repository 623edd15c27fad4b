"""The backend setting and the 'auto' rule (``core_se3.backend``).

'auto' evaluates on NumPy until the numba time it would have saved (``iteration_saving`` per
tangent evaluation) reaches ``NUMBA_START_COST``, then on numba for the rest of the process.
These tests reset the process-wide count (``_Rent``) around themselves.
"""
import numpy as np
import pytest

from core_se3 import Material, Problem, backend, mesh
from core_se3.errors import OptionError

# the switch itself needs numba; without it 'auto' is NumPy (test_without_numba_auto_is_numpy)
needs_numba = pytest.mark.skipif(not backend.numba_available(), reason="the switch to numba needs numba")


@pytest.fixture
def fresh_rent(monkeypatch):
    """A process whose 'auto' problems have done no work yet."""
    monkeypatch.setattr(backend._Rent, "saved", 0.0)
    monkeypatch.setattr(backend._Rent, "switched", False)
    monkeypatch.setattr(backend._Rent, "cold", False)            # a warm kernel cache
    monkeypatch.delenv("CORE_SE3_BACKEND", raising=False)
    for var in backend._RANK_VARIABLES:
        monkeypatch.delenv(var, raising=False)
    backend.set_backend(None)
    yield backend._Rent
    backend.set_backend(None)


def _cantilever(nx=8, **kw):
    p = Problem(mesh.rectangle(10.0, 1.0, nx, 1), Material(1.2e6, 0.0, 0.1), **kw)
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 4.0))
    p.add_probe("tip", "x1")
    return p


def _iterations(res):
    return sum(s.iterations for s in res.steps)


@needs_numba
def test_auto_is_the_default_and_starts_on_numpy(fresh_rent):
    p = _cantilever()
    assert p.backend_setting == "auto" and p.backend == "numpy"
    res = p.solve(steps=4)
    # one charge per tangent evaluation: the Newton iterations of the converged tries here, and
    # the end check's count of negative eigenvalues (solvers.newton._end_check: one tangent)
    its = _iterations(res) + 1
    assert fresh_rent.saved == pytest.approx(its * backend.iteration_saving(p.mesh.n_elements), rel=1e-12)
    assert fresh_rent.saved < backend.NUMBA_START_COST and p.backend == "numpy"


@needs_numba
def test_auto_switches_to_numba_once_the_start_would_have_paid_and_stays(fresh_rent):
    p = _cantilever()
    ref = _cantilever(backend="numpy").solve(steps=4).final.probes["tip"]["u"]
    solves = 0
    while p.backend == "numpy":
        res = p.solve(steps=4)
        solves += 1
        assert solves < 100
    # the count at the switch: the first charge at or past the start cost
    assert fresh_rent.switched
    assert fresh_rent.saved >= backend.NUMBA_START_COST
    assert fresh_rent.saved < backend.NUMBA_START_COST + backend.iteration_saving(p.mesh.n_elements) + 1e-15
    per_solve = (_iterations(res) + 1) * backend.iteration_saving(p.mesh.n_elements)   # + the end check
    assert solves == int(np.ceil(backend.NUMBA_START_COST / per_solve - 1e-12))
    saved = fresh_rent.saved
    res = p.solve(steps=4)
    assert p.backend == "numba" and fresh_rent.saved == saved         # no more counting
    assert p._compiled is not None                                     # the kernels evaluated
    # both backends are the same equations (tests/test_kernels.py): the same state to round-off
    assert np.abs(res.final.probes["tip"]["u"] - ref).max() <= 1e-10 * np.abs(ref).max()
    # a new 'auto' problem of the same process starts on numba
    assert _cantilever().backend == "numba"


@needs_numba
def test_fixed_settings_are_not_counted_and_not_switched(fresh_rent):
    for name in ("numpy", "numba"):
        p = _cantilever(backend=name)
        p.solve(steps=2)
        assert p.backend == name and p.backend_setting == name
    assert fresh_rent.saved == 0.0 and not fresh_rent.switched


@needs_numba
def test_a_big_mesh_switches_within_its_first_iterations(fresh_rent):
    """The count grows with the mesh: 10^4 elements pass the start cost in 3 iterations."""
    m = 10_000
    k = int(np.ceil(backend.NUMBA_START_COST / backend.iteration_saving(m)))
    assert k <= 3
    for _ in range(k):
        backend.charge(m)
    assert backend.active("auto") == "numba"


@needs_numba
def test_a_distributed_run_takes_numba_at_once(fresh_rent, monkeypatch):
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    assert backend.active("auto") == "numba"


def test_without_numba_auto_is_numpy(fresh_rent, monkeypatch):
    monkeypatch.setattr(backend, "numba_available", lambda: False)
    fresh_rent.switched = True
    assert backend.active("auto") == "numpy"
    assert backend.default_backend() == "numpy"
    with pytest.raises(OptionError, match="needs numba"):
        backend.resolve("numba")


@needs_numba
def test_settings_from_the_environment_and_set_backend(fresh_rent, monkeypatch):
    monkeypatch.setenv("CORE_SE3_BACKEND", " NumPy ")
    assert _cantilever().backend_setting == "numpy"
    backend.set_backend("numba")
    assert _cantilever().backend_setting == "numba"
    backend.set_backend(None)
    monkeypatch.setenv("CORE_SE3_BACKEND", "auto")
    assert _cantilever().backend_setting == "auto"
    monkeypatch.setenv("CORE_SE3_BACKEND", "cuda")
    with pytest.raises(OptionError, match="unknown backend 'cuda'; choose 'auto', 'numba' or 'numpy'"):
        _cantilever()


@needs_numba
def test_setting_the_backend_of_a_problem(fresh_rent):
    p = _cantilever()
    p.backend = "numba"
    assert p.backend == "numba" and p.backend_setting == "numba"
    with pytest.raises(OptionError, match="unknown backend"):
        p.backend = "gpu"


@needs_numba
def test_each_step_records_the_backend_that_evaluated_it(fresh_rent, monkeypatch):
    """A start cost passed within the first solve: its steps are recorded on NumPy up to the
    switch and on numba after it (``StepResult.backend``, the step records' ``backend``)."""
    from core_se3.results import format_backends, step_record
    p = _cantilever()
    # one charge per Newton iteration (test above): the 11th switches, in the step whose
    # iterations reach it (here step 3 of 4: 5, 5, 5, 4 iterations)
    monkeypatch.setattr(backend, "NUMBA_START_COST", 10.5 * backend.iteration_saving(p.mesh.n_elements))
    res = p.solve(steps=4)
    k = int(np.searchsorted(np.cumsum([s.iterations for s in res.steps[1:]]), 11)) + 1
    assert k == 3
    assert [s.backend for s in res.steps] == ["numpy"] * k + ["numba"] * (len(res.steps) - k)
    recs = [step_record(s, None) for s in res.steps]
    assert format_backends(recs) == "backend: numpy for steps 0-2, numba for steps 3-4"
    assert format_backends([step_record(s, None) for s in _cantilever().solve(steps=1).steps]) == "backend: numba"


@needs_numba
def test_the_compiled_evaluation_is_not_taken_for_a_new_assembler_at_an_old_address():
    """The compiled parts were cached under the id() of the assembler they were built for, and
    not kept alive: linear analysis evaluates on a temporary assembler of all dofs, and the
    problem's own assembler, made next, often took its address (15 of 20 trials) and got its
    parts -- a residual on all 162 dofs instead of the 144 free ones (a Newton solve after
    solve_linear failed with a ValueError of mismatched sizes on the 64x64 hemisphere).  Each trial
    frees the temporary assembler just before the problem's is made."""
    from core_se3.assembly import Assembler
    for _ in range(20):
        p = Problem(mesh.rectangle(10.0, 1.0, 8, 2), Material(1.2e6, 0.3, 0.1), backend="numba")
        p.clamp("x0")
        p.add_nodal_load("x1", force=(0.0, 0.0, 1e-3))
        every = Assembler(p.mesh, np.ones(6 * p.mesh.n_nodes, bool))
        assert p.evaluate(p.mesh.g0, 0.0, assembler=every).r.size == 162
        del every
        asm = p.assembler()
        assert p.evaluate(p.mesh.g0, 1.0).r.size == int(asm.free.sum()) == 144
