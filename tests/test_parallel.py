"""The distributed solver (core_se3.parallel, issue 17).

* One and two ranks agree with the serial solver (``mpirun -n 1``, ``-n 2`` in a subprocess; one
  rank shares the kernels' CSR with PETSc, two assemble through COO): sze-hemisphere (in
  load control: the catalogue traces it by arc length, which runs serially), magnetic-gripper,
  a 100x100 plate under follower pressure, and three contact cases (contact-propped, the
  gripper grasping a sphere, a ball smaller than an element held by a face sample) give the
  same probes and contact forces to 1e-10 relative at every step and the same Newton iterations per step; a scenario run interrupted after two steps and
  resumed on two ranks ends in the bits of an uninterrupted one.  Skipped without mpi4py,
  petsc4py or mpirun.
* The checks of accepted steps (issue 29, docs/STEPS.md) run distributed as serially: the snap
  check of contact steps (the same probes, tries and snap as the serial run), the end check and
  inertia_check on the sandwich strip's even crossings (the ranks count the negative eigenvalues
  of sym K with MUMPS: the serial counts; the same stops and messages), the stability check
  (det K's sign from MUMPS' determinant).
* The decomposition, serially: the ranks' local problems (every load kind) sum to the whole
  problem's forces and tangent; one rank's PETSc matrix is the kernels' CSR (its free block the
  serial K_ff bit for bit, held dofs identity, no copy); partitions are balanced; the rigid-body
  modes are the null space of the tangent of a free, unloaded plate (the near-null space given
  to GAMG).
* Designs on two ranks (design-tip-angle, design-field-direction) reach the serial designs.
* A serial run does not import mpi4py or petsc4py.
"""
import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, lie, mesh
from core_se3.errors import ConvergenceError
from core_se3.errors import ConvergenceError, OptionError, ParallelError
from core_se3.model import Load, LoadEvaluation, UniformField, make_obstacle
from core_se3.parallel import (RunSetup, distributed_solve, local_problem, localize_load, partition_elements, rcb,
                               subdomain)
from core_se3.parallel.comm import SerialComm
from core_se3.parallel.system import rigid_body_modes

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from parallel_cases import CASES, DESIGNS, FAILS, ONE_SIDED, PROBES, STOPS, build  # noqa: E402

HAVE_MPI = (importlib.util.find_spec("mpi4py") is not None and importlib.util.find_spec("petsc4py") is not None
            and shutil.which("mpirun") is not None)


def mpi_env():
    env = dict(os.environ)
    env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1", OMPI_MCA_mpi_yield_when_idle="1", OMPI_MCA_rmaps_base_oversubscribe="1",
               PYTHONPATH=ROOT + os.pathsep + env.get("PYTHONPATH", ""))
    return env


def _driver(tmp_path_factory, ranks, *names, timeout=600):
    if not HAVE_MPI:
        pytest.skip("needs mpi4py, petsc4py and mpirun")
    out = tmp_path_factory.mktemp("par") / "out.json"
    cmd = ["mpirun", "-n", str(ranks), "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS",
           sys.executable, os.path.join(HERE, "parallel_driver.py"), str(out), *names]
    p = subprocess.Popen(cmd, env=mpi_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                         start_new_session=True)
    try:
        stdout, stderr = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:         # ranks that hang: mpirun and its ranks ended, the test fails
        os.killpg(p.pid, signal.SIGKILL)
        stdout, stderr = p.communicate()
        pytest.fail(f"mpirun -n {ranks} {' '.join(names)} did not finish in {timeout} s (hung ranks)\n" + stdout[-2000:])
    assert p.returncode == 0, stdout[-3000:] + stderr[-3000:]
    return json.loads(out.read_text())


@pytest.fixture(scope="module")
def two_ranks(tmp_path_factory):
    return _driver(tmp_path_factory, 2, *CASES, *DESIGNS, *STOPS, "sandwich-stable", "counts", "resume")


@pytest.fixture(scope="module")
def one_rank(tmp_path_factory):
    """The distributed solver on one rank: PETSc's matrix shares the kernels' CSR of all dofs
    (parallel.matrix.SharedCsrMatrix) instead of the COO assembly of several ranks."""
    return _driver(tmp_path_factory, 1, *CASES, *STOPS, "sandwich-stable", "counts")


@pytest.mark.parametrize("ranks", [1, 2])
@pytest.mark.parametrize("name", list(CASES))
def test_distributed_runs_agree_with_serial(request, ranks, name):
    _agrees_with_serial(request.getfixturevalue({1: "one_rank", 2: "two_ranks"}[ranks]), ranks, name)


@pytest.fixture(scope="module")
def one_sided(tmp_path_factory):
    """Two ranks on the strips whose loads one rank holds (``ONE_SIDED``) and the runs that fail
    (``FAILS``); a hang fails in 300 s."""
    return _driver(tmp_path_factory, 2, *ONE_SIDED, *FAILS, timeout=300)


def test_a_field_turning_a_magnet_on_one_rank_splits_every_ranks_steps_as_serially(one_sided):
    """A try is split where a field turns by more than MAX_LOAD_TURN (pi/4) within it: the turn is
    measured on the whole problem's loads on every rank.  Each rank measured it on its own loads,
    so the rank without the magnet (at the tip of a 12 x 1 strip) did not split the 1 rad steps
    that the other split in two: the ranks iterated at different load factors and hung (a
    scenario of the same kind: 'running' after 200 s on two ranks, 3 s serially)."""
    _agrees_with_serial(one_sided, 2, "magnet-turning-tip")


def test_a_follower_force_on_one_ranks_nodes_is_left_uncounted_on_every_rank(one_sided):
    """inertia_check counts the negative eigenvalues of sym K (collective) where the loads are
    conservative by their kinds, judged on the whole problem's loads on every rank: each rank
    judged its own, so the rank without the follower tip force counted and the other did not,
    and the ranks hung."""
    _agrees_with_serial(one_sided, 2, "follower-tip-inertia")


@pytest.mark.parametrize("name", list(FAILS))
def test_a_failed_contact_run_gives_the_serial_message_on_the_ranks(one_sided, name):
    """Runs whose cut-backs run out stop on two ranks with the serial message.  A roller rising
    under a plate under its weight (fails at 0.406): serially without a probable cause (the
    limit-point hint is path following's, which refuses contact), on two ranks it named 'a limit
    point' at S_p = 0.0166 and arc length.  A roller pressing into the clamped edge x1: serially
    'presses 0.015 into node 8, whose translations a support holds'; on two ranks no cause (rank
    1 holds x1, rank 0 writes; the node was named in rank 1's own ids and looked up in the whole
    mesh's supports)."""
    prob, steps, kw = build(name)
    with pytest.raises(ConvergenceError) as exc:
        prob.solve(steps=steps, solver="serial", **kw)
    assert ("Probable cause" in str(exc.value)) == (name == "press-held")
    assert one_sided[name]["message"] == str(exc.value)
    assert one_sided[name]["lam"] == [s.load_factor for s in exc.value.result.steps]


def _agrees_with_serial(run, ranks, name):
    """The distributed run ``run[name]`` on ``ranks`` took the serial run's tries, checks and
    critical points, and reached its probes, contact forces and frames to 1e-10."""
    prob, steps, kw = build(name)
    ser = prob.solve(steps=steps, solver="serial", **kw)      # every check on, as distributed
    par = run[name]
    assert run["ranks"] == ranks and par["parallel"]["ranks"] == ranks
    assert par["iterations"] == [s.iterations for s in ser.steps]
    assert par["attempts"] == [s.attempts for s in ser.steps[1:]]          # the same tries, probes included
    for a, b in zip(par["checks"], [s.checks for s in ser.steps[1:]]):
        assert a.keys() == b.keys() and all(a[k] == b[k] for k in a if k not in ("contraction", "travel")), (a, b)
    assert len(par["critical_points"]) == len(ser.critical_points)
    for a, b in zip(par["critical_points"], ser.critical_points):
        assert a["kind"] == b.kind and a["step"] == b.step and a["lam_bracket"] == list(b.lam_bracket)
        if b.kind == "snap":                                    # the node may differ on a tie to round-off
            assert abs(a["travel"] / b.travel - 1) < 1e-10 and a["node"] in prob.mesh.node_set("x1")
    assert np.allclose(par["lam"], [s.load_factor for s in ser.steps], rtol=0, atol=1e-14)
    for k, st in enumerate(ser.steps[1:], start=1):
        for probe, v in st.probes.items():
            u = np.asarray(v["u"])
            err = np.linalg.norm(np.asarray(par["probes"][k][probe]) - u) / np.linalg.norm(u)
            assert err < 1e-10, (name, k, probe, err)
        for obstacle, c in (st.contact or {}).items():             # the contact force on each obstacle
            F = np.asarray(c["force"])                              # (relative to its largest on the path)
            scale = max(np.linalg.norm(s.contact[obstacle]["force"]) for s in ser.steps[1:])
            if scale == 0:                                          # never touched (jumping-cantilever)
                assert not np.any(par["contact"][k][obstacle])
                continue
            err = np.linalg.norm(np.asarray(par["contact"][k][obstacle]) - F) / scale
            # the force is the penalty stiffness k A times the gap: a round-off eps |u| of the
            # positions (a different factorisation) moves it by k A eps |u|, up to 2.4e-10 of
            # the largest force in contact-propped (k A |u| / F = 1.1e6)
            ld = next(ld for ld in prob.loads if getattr(ld, "name", None) == obstacle)
            u_max = np.abs(np.asarray(ser.final.g)[:, :3, 3] - prob.mesh.g0[:, :3, 3]).max()
            roundoff = 10 * np.finfo(float).eps * float((ld.k * ld.A).max()) * u_max / scale
            assert err < max(1e-10, roundoff), (name, k, obstacle, err, roundoff)
    g = np.asarray(ser.final.g).ravel()[::7]
    assert np.abs(np.asarray(par["g"]) - g).max() < 1e-10 * np.abs(g).max()


def test_contact_cases_that_probe_are_compared_with_the_snap_check():
    """The comparison above runs the snap check on both sides on cases where it acts: the
    gripper's grasp probes some of its steps, the jumping cantilever reports its snap."""
    prob, steps, kw = build("magnetic-gripper-grasp")
    res = prob.solve(steps=steps, solver="serial", **kw)
    assert sum(s.checks["snap_probes"] for s in res.steps[1:]) >= 1
    prob, steps, kw = build("jumping-cantilever")
    assert [cp.kind for cp in prob.solve(steps=steps, solver="serial", **kw).critical_points] == ["snap"]


@pytest.mark.parametrize("ranks", [1, 2])
@pytest.mark.parametrize("name", list(STOPS))
def test_distributed_runs_stop_where_serial_runs_stop(request, ranks, name):
    """The sandwich strip to 0.2 C w (tests/test_step_checks.py): its even crossings, which the
    sign of det K does not show, stop the distributed run as they stop the serial one -- the
    end check in 1, 2, 5 and 10 steps ("rose from 0 to 12 / 6 / 4 / 2 between load factors 0
    and 1 / 0.5 / 0.2 / 0.1", the steps before kept), inertia_check at the first crossing
    (0.0426), and without the end check the stability check at the sign change of det K in 5
    steps (0.533, MUMPS' determinant) -- with the same message.  Before, the distributed runs
    exited 0 at load factor 1 in all of them (neither check ran distributed)."""
    run = request.getfixturevalue({1: "one_rank", 2: "two_ranks"}[ranks])
    prob, steps, kw = build(name)
    with pytest.raises(ConvergenceError) as exc:
        prob.solve(steps=steps, solver="serial", **kw)
    par = run[name]
    assert par["message"] == str(exc.value)
    assert par["lam"] == [s.load_factor for s in exc.value.result.steps]
    assert "crossed a critical point" in par["message"]
    assert run["sandwich-stable"] == dict(message=None, lam=[0.0, 0.5, 1.0], critical_points=0)


@pytest.mark.parametrize("name", list(PROBES))
def test_the_midpoint_probe_refuses_on_the_ranks_as_serially(tmp_path_factory, name):
    """The midpoint probe (docs/STEPS.md) runs distributed as serially: fuzz problem 144's try
    0.5 -> 1 turns a node by 6.0 rad (the largest over the two ranks), its probe at 0.75 lands on
    det K -1 (MUMPS' determinant), and the run stops at the limit point with the serial message
    -- but for the residual of its last try, which wanders for 30 iterations near the limit point
    (8.88e-2 serially, 8.87e-2 on two ranks: round-off)."""
    par = _driver(tmp_path_factory, 2, name)[name]
    prob, steps, kw = build(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError) as exc:
            prob.solve(steps=steps, solver="serial", **kw)
    def masked(m):
        return re.sub(r"residual [0-9.e+-]+", "residual R", m)
    assert masked(par["message"]) == masked(str(exc.value)) and "after 12 cut-backs" in par["message"]
    assert par["lam"] == [s.load_factor for s in exc.value.result.steps]


@pytest.mark.parametrize("ranks", [1, 2])
def test_the_ranks_count_the_negative_eigenvalues_as_serially(request, ranks):
    """MUMPS' negative pivots of the distributed sym K (never gathered) at the sandwich strip's
    five-step states (no check stopping it) are the serial counts (stability.negative_count)."""
    from core_se3.solvers.stability import negative_count
    run = request.getfixturevalue({1: "one_rank", 2: "two_ranks"}[ranks])
    prob, _, _ = build("sandwich-5")
    ser = prob.solve(steps=5, solver="serial", end_check=False, limit_check=False)
    counts = [negative_count(prob, s.g, s.load_factor) for s in ser.steps]
    assert counts == [0, 4, 6, 7, 8, 12] and run["counts"] == counts


@pytest.fixture(scope="module")
def two_ranks_small(tmp_path_factory):
    return _driver(tmp_path_factory, 2, "first-step-buckling", "roof-counts")


def test_a_first_step_onto_the_start_tangents_singular_load_goes_on_two_ranks_as_on_one(two_ranks_small):
    """The clamped 6-element strip whose first step lands on its start tangent's singular load
    (P = 2 EI/L^2, the equilibrated condition number 5e16; not a critical point of the path:
    tests/test_step_checks.py): serially the try is cut back and the run stops at Euler's
    bifurcation; two ranks do the same, step for step, with the same message.  Found: two ranks
    went on to load factor 1 (the first solve's random right-hand side grew 6.3e14 there, 3.6e15
    serially, against the limit 1e15), and the serial run stopped at 0.5 calling it a buckling load."""
    from test_step_checks import _first_step_on_buckling_load
    with pytest.raises(ConvergenceError) as exc:
        _first_step_on_buckling_load().solve(steps=2, solver="serial")
    lam = [float(s.load_factor) for s in exc.value.result.steps]
    assert two_ranks_small["first-step-buckling"] == dict(error="ConvergenceError", message=str(exc.value), lam=lam)
    assert "bifurcation" in str(exc.value)


@pytest.mark.parametrize("follower", [False, True])
def test_two_ranks_count_on_a_shell_held_on_symmetry_planes(two_ranks_small, follower):
    """The Scordelis-Lo roof 4x4 held on its symmetry planes: max |K - K^T| is 2.3e-5 of max |K|,
    all in the held nodes' diagonal blocks (the reactions' 1/2 ad*; 7e-16 outside them). The ranks
    leave those blocks out of the asymmetry test as serially, so they count its negative
    eigenvalues (0 at every step, the serial counts); with a follower edge force (1.7e-5 lam
    outside them) they give None as serially (at every state, the unloaded start too: a follower
    is not conservative by its kind, ``model.base.conservative_loads``).  Found: the ranks' K - K^T
    was 0 (petsc4py's ``K.transpose()`` transposes K in place and returns it), so the test could
    not fail and a follower load was counted (0 at every step on 1 and 2 ranks, serially None)."""
    from core_se3.solvers.stability import negative_count
    from parallel_cases import roof_on_symmetry_planes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                  # the symmetry planes' drift warning
        prob = roof_on_symmetry_planes(follower)
        ser = prob.solve(steps=4, solver="serial")
    counts = [negative_count(prob, s.g, s.load_factor) for s in ser.steps]
    assert counts == ([None] * 5 if follower else [0] * 5)
    assert two_ranks_small["roof-counts" + "-follower" * follower] == counts


def test_an_iterative_solver_says_which_checks_it_cannot_do(caplog):
    """GAMG gives no determinant and no inertia: the run warns that the stability check's sign
    test and the end check are off (not silently); MUMPS runs them without a word."""
    if importlib.util.find_spec("petsc4py") is None:
        pytest.skip("needs petsc4py")
    import logging
    prob, _, _ = build("sandwich-stable")
    with caplog.at_level(logging.WARNING):
        prob.solve(steps=1, solver="distributed", linear="mumps")
        assert not [r for r in caplog.records if "is iterative" in r.getMessage()]
        prob.solve(steps=1, solver="distributed", linear="gamg")
    (msg,) = [r.getMessage() for r in caplog.records if "is iterative" in r.getMessage()]
    assert "stability check" in msg and "end check" in msg and "limit_check = false" in msg


def test_two_ranks_resume_and_output(two_ranks):
    r = two_ranks["resume"]
    # MUMPS over two ranks assembles its fronts in message-arrival order: two runs of the same
    # steps agree to rounding (a few 1e-15 measured), not bit for bit as the serial resume does
    assert r["difference"] < 1e-12 and r["steps"] == 5
    assert r["files"] == [".core-se3-manifest.json", "checkpoint.npz", "results.json", "vtu"]
    assert r["vtu"] == ["series.pvd"] + [f"step_{k:04d}.vtu" for k in range(5)]


# ---------------------------------------------------------------------------- serially ------
class _NodalCouple(Load):
    """A load of one's own with the ``localized`` hook of docs/EXTENDING.md (a dead couple
    area_i c on every node)."""

    def __init__(self, n, area, c):
        self.area, self.c, self.n = np.asarray(area, float), np.asarray(c, float), n

    def evaluate(self, g, lam, tangent=True):
        Mb = lam * self.area[:, None] * np.einsum("nji,j->ni", g[:, :3, :3], self.c)
        f = np.zeros((self.n, 6))
        f[:, 3:] = Mb
        K = np.zeros((self.n, 6, 6))
        K[:, 3:, 3:] = -lie.hat3(Mb)
        return LoadEvaluation(f, K if tangent else None)

    def localized(self, part):
        pos, loc = part.owned_local(np.arange(self.n))
        area = np.zeros(part.mesh.n_nodes)
        area[loc] = self.area[pos]
        return [_NodalCouple(part.mesh.n_nodes, area, self.c)]


def _problem():
    """A plate with every kind of load the decomposition handles."""
    m = mesh.rectangle(2.0, 1.0, 8, 5)
    p = Problem(m, Material(1e4, 0.3, 0.02, rho=2.0))
    p.clamp("x0")
    p.fix("y0", [1])
    p.add_edge_force("x1", (0.0, 0.3, 1.0))
    p.add_edge_moment("y1", (0.1, 0.0, 0.0), follower=True)
    p.add_nodal_load([7, 30], force=(1.0, 0.0, 0.0))
    p.add_pressure(0.4, follower=True)
    p.add_pressure(0.2, elements=np.arange(10))
    p.add_gravity(g=(0.0, 0.0, -1.0))
    p.add_magnetic((0.0, 0.0, 0.1), UniformField((0.1, 0.0, 0.0)), elements=np.arange(20, 40), mu0=1.0)
    p.add_lab_support([40, 41], [[0.0, 0.0, 1.0]], 10.0)
    p.add_lab_tilt_support([42], (1.0, 0.0, 0.0), 5.0)
    p.add_rotation_component_support([43], (0.0, 1.0, 0.0), 5.0)
    p.add(_NodalCouple(m.n_nodes, np.linspace(0.0, 1.0, m.n_nodes), (0.0, 0.2, 0.1)))
    # a ball smaller than an element under element 21 (rank 2 of rcb's three; three of its nodes
    # rank 1's): its face sample carries the random state below, no node touches it
    p.add_obstacle(make_obstacle("sphere", centre=(1.375, 0.0, -0.07), radius=0.06), name="pin")
    # a sphere 0.002 below the lower face at (1, 0): the random state below presses nodes into it
    p.add_obstacle(make_obstacle("sphere", centre=(1.0, 0.0, -3.012), radius=3.0))
    return p


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_local_problems_sum_to_the_whole(backend):
    p = _problem()
    p.backend = backend
    rng = np.random.default_rng(3)
    g = p.mesh.g0 @ lie.exp(0.05 * rng.standard_normal((p.mesh.n_nodes, 6)))
    ev = p.evaluate(g, 0.7)
    n = p.mesh.n_nodes
    part = rcb(p.mesh.X[p.mesh.quads].mean(1), 3)
    r_int, f_ext = np.zeros((n, 6)), np.zeros((n, 6))
    K = np.zeros((6 * n, 6 * n))
    for rank in range(3):
        sub = subdomain(p.mesh, part, rank, 3)
        loc = local_problem(p, sub)
        loc.backend = backend
        le = loc.evaluate(g[sub.nodes], 0.7)
        np.add.at(r_int, sub.nodes, le.r_int)
        np.add.at(f_ext, sub.nodes, le.f_ext)
        dof = (6 * sub.nodes[:, None] + np.arange(6)).ravel()[loc.assembler().free]
        Kl = le.K.tocoo()
        np.add.at(K, (dof[Kl.row], dof[Kl.col]), Kl.data)
    free = p.assembler().free
    contact = p.loads[-1].evaluate(g, 0.7).f
    assert np.count_nonzero(np.abs(contact).sum(1)) >= 3           # the contact takes part
    pin = p.loads[-2]                                              # and the face sample (alone)
    assert (pin.face_state(g, 0.7)[1] > 0).sum() == 1 and pin.state(g, 0.7)[4].max() == 0
    assert np.abs(r_int - ev.r_int).max() < 1e-12 * np.abs(ev.r_int).max()
    assert np.abs(f_ext - ev.f_ext).max() < 1e-12 * np.abs(ev.f_ext).max()
    Kg = ev.K.toarray()
    assert np.abs(K[np.ix_(free, free)] - Kg).max() < 1e-12 * np.abs(Kg).max()


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_every_ranks_element_is_built_on_the_serial_gauge(backend):
    """Nodal frames turning about the normal (an annulus, d1 at random): each rank's element is
    built on the whole mesh's gauge (``Mesh.gauge_angles`` of its nodes, not its sub-mesh's own,
    which differs by a constant per part), and the local forces and tangents sum to the serial ones."""
    from core_se3.mesh.gauge import turned_about_normal
    a = mesh.annulus(1.0, 2.0, 1.0, 4, 6)
    m = mesh.Mesh(turned_about_normal(a.g0, np.random.default_rng(2).uniform(-1, 1, a.n_nodes)), a.quads,
                  edges=a.edges)
    p = Problem(m, Material(1e4, 0.3, 0.05), backend=backend)
    p.clamp("x0")
    g = m.g0 @ lie.exp(0.05 * np.random.default_rng(3).standard_normal((m.n_nodes, 6)))
    ev = p.evaluate(g, 1.0)
    part = rcb(m.X[m.quads].mean(1), 2)
    r_int, K = np.zeros((m.n_nodes, 6)), np.zeros((6 * m.n_nodes, 6 * m.n_nodes))
    for rank in range(2):
        sub = subdomain(m, part, rank, 2)
        loc = local_problem(p, sub)
        loc.backend = backend
        assert np.array_equal(loc.element.gauge, p.element.gauge[sub.nodes])
        le = loc.evaluate(g[sub.nodes], 1.0)
        np.add.at(r_int, sub.nodes, le.r_int)
        dof = (6 * sub.nodes[:, None] + np.arange(6)).ravel()[loc.assembler().free]
        Kl = le.K.tocoo()
        np.add.at(K, (dof[Kl.row], dof[Kl.col]), Kl.data)
    free = p.assembler().free
    assert np.abs(r_int - ev.r_int).max() < 1e-12 * np.abs(ev.r_int).max()
    Kg = ev.K.toarray()
    assert np.abs(K[np.ix_(free, free)] - Kg).max() < 1e-12 * np.abs(Kg).max()


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_a_ranks_edge_turning_by_pi_is_named_by_the_whole_meshs_nodes(backend):
    """A step that fails on an edge turning by pi names the edge's nodes in the whole mesh's ids
    on a rank's part too (the scenario strip of 12 x 3 under a tip force 1000 times too large
    failed naming edge [22, 23] on two ranks for the serial [46, 47]: the rank's local ids)."""
    from core_se3.errors import ElementTooDistortedError
    p = Problem(mesh.rectangle(3.0, 1.0, 6, 2), Material(1e4, 0.3, 0.05), backend=backend)
    p.clamp("x0")
    g = p.mesh.g0.copy()
    g[20, :3, :3] = lie.exp_so3([0.0, 0.0, 3.1])             # node 20 (on x1) turned by 3.1 rad
    with pytest.raises(ElementTooDistortedError) as serial:
        p.evaluate(g, 1.0)
    assert re.match(r"edge \[(13, 20|19, 20|20, 13|20, 19)\] turns by 3.100", str(serial.value))
    part = rcb(p.mesh.X[p.mesh.quads].mean(1), 2)
    sub = subdomain(p.mesh, part, 1, 2)                     # the x1 half: node 20 is not local node 20
    assert 20 in sub.nodes and sub.g2l[20] != 20
    loc = local_problem(p, sub)
    loc.backend = backend
    with pytest.raises(ElementTooDistortedError) as ranks:
        loc.evaluate(g[sub.nodes], 1.0)
    assert str(ranks.value)[:30] == str(serial.value)[:30]


def test_a_ranks_turned_lab_rotation_node_is_named_by_the_whole_meshs_id():
    """A lab_rotation spring's node turned by nearly pi is named in the whole mesh's ids on a
    rank's part (it was the rank's local id: node 2 for node 20)."""
    from core_se3.errors import ElementTooDistortedError
    p = Problem(mesh.rectangle(3.0, 1.0, 6, 2), Material(1e4, 0.3, 0.05))
    p.clamp("x0")
    p.add_rotation_component_support([20], (0.0, 1.0, 0.0), 5.0, name="roller")
    g = p.mesh.g0.copy()
    g[20, :3, :3] = lie.exp_so3([0.0, 3.05, 0.0])
    sub = subdomain(p.mesh, rcb(p.mesh.X[p.mesh.quads].mean(1), 2), 1, 2)
    spring = localize_load(p.loads[0], sub)[0]
    assert sub.g2l[20] != 20 and spring.nodes.tolist() == [sub.g2l[20]]
    with pytest.raises(ElementTooDistortedError, match="node 20 has turned by 3.050 rad"):
        spring.evaluate(g[sub.nodes], 1.0)


def test_one_rank_shares_the_kernels_csr_with_petsc():
    """One rank: PETSc's matrix is the compiled evaluation's CSR of all dofs, not a copy; after
    ``set`` its free block is the serial tangent K_ff entry for entry and every held dof is an
    identity row and column (the layout of the COO path of several ranks)."""
    if importlib.util.find_spec("petsc4py") is None:
        pytest.skip("needs petsc4py")
    from core_se3.parallel.local import PatternAssembler
    from core_se3.parallel.matrix import SharedCsrMatrix
    if importlib.util.find_spec("numba") is None:
        pytest.skip("needs numba: only the compiled evaluation writes into a CSR it is given")
    p = _problem()
    p.backend = "numba"          # not 'auto': its switch depends on what the process ran before
    rng = np.random.default_rng(5)
    g = p.mesh.g0 @ lie.exp(0.05 * rng.standard_normal((p.mesh.n_nodes, 6)))
    ref = p.evaluate(g, 0.7).K.toarray()                            # K_ff of the free dofs
    free = p.assembler().free
    everything = PatternAssembler(p.mesh, np.ones_like(free))
    pat = everything.pattern()
    A = SharedCsrMatrix(pat.indptr, pat.indices, ~free, bsize=6)
    p.evaluate(g, 0.7, assembler=everything, out=A.data)           # the kernels write PETSc's values
    M = A.set()
    assert M.getBlockSize() == 6                                    # the multigrid's 6-dof nodes
    dense = np.zeros((6 * p.mesh.n_nodes,) * 2)
    ip, ix, v = M.getValuesCSR()
    dense[np.repeat(np.arange(len(ip) - 1), np.diff(ip)), ix] = v
    assert np.array_equal(dense[np.ix_(free, free)], ref)          # the same sums, bit for bit
    held = np.flatnonzero(~free)
    assert len(held) > 0
    assert np.array_equal(dense[held][:, held], np.eye(len(held)))
    assert not dense[np.ix_(held, np.flatnonzero(free))].any() and not dense[np.ix_(free, held)].any()
    A.data[0] += 1.0                                                # no copy: PETSc sees the change
    assert M.getValue(0, int(pat.indices[0])) == dense[0, pat.indices[0]] + 1.0


def test_the_distributed_set_up_reaches_the_run_once():
    """Problem.solve's linear/partition keywords and setup= (a RunSetup or a dict) reach the run
    alike; the set-up given both ways, or a set-up keyword given to distributed_solve directly,
    is an OptionError (not one of the two silently dropped)."""
    if importlib.util.find_spec("petsc4py") is None:
        pytest.skip("needs petsc4py")
    p = Problem(mesh.rectangle(2.0, 1.0, 4, 2), Material(1e4, 0.3, 0.02))
    p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1e-3)); p.add_probe("tip", "x1")
    a = p.solve(steps=1, solver="distributed", linear="mumps", partition="rcb")
    b = p.solve(steps=1, solver="distributed", setup=dict(linear="mumps", partition="rcb"))
    c = distributed_solve(p, steps=1, setup=RunSetup(linear="mumps", partition="rcb"))
    assert a.parallel["linear"] == b.parallel["linear"] == c.parallel["linear"] == "mumps"
    assert np.array_equal(a.final.g, b.final.g) and np.array_equal(a.final.g, c.final.g)
    with pytest.raises(OptionError, match="given twice"):
        p.solve(steps=1, solver="distributed", linear="gamg", setup=dict(linear="mumps"))
    with pytest.raises(OptionError, match="setup=RunSetup"):
        distributed_solve(p, steps=1, linear="gamg")


def test_a_load_without_a_distributed_form_is_refused():
    class Bare(Load):
        name = "bare"

        def evaluate(self, g, lam, tangent=True):
            return LoadEvaluation(np.zeros((len(g), 6)))
    p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    p.add(Bare())
    with pytest.raises(ParallelError, match="'bare' .*localized"):
        local_problem(p, subdomain(p.mesh, np.array([0, 1]), 0, 2))


def test_a_partitioner_petsc_lacks_is_named_with_the_choices():
    """A partitioner this PETSc was built without ([solver] partition = "parmetis" on Debian's)
    says so and names the choices (it was PETSc's 'Unknown partitioning type' alone)."""
    petsc = pytest.importorskip("petsc4py.PETSc")
    from core_se3.parallel.partition import _petsc_partition
    m = mesh.rectangle(2.0, 1.0, 4, 1)
    try:
        _petsc_partition(m, SerialComm(), "parmetis")
    except ParallelError as exc:
        assert "built without it" in str(exc) and "'auto', 'ptscotch' or 'rcb'" in str(exc)
    else:
        pytest.skip("this PETSc has ParMETIS")


def test_partitions_are_balanced_and_cover_every_element():
    m = mesh.rectangle(3.0, 1.0, 30, 10)
    for P in (2, 3, 5):
        part = rcb(m.X[m.quads].mean(1), P)
        counts = np.bincount(part, minlength=P)
        assert counts.sum() == 300 and counts.max() - counts.min() <= 1
    assert partition_elements(m, SerialComm()).tolist() == [0] * 300


def test_rigid_body_modes_are_the_null_space_of_a_free_plate():
    p = Problem(mesh.rectangle(2.0, 1.0, 6, 3), Material(1e4, 0.3, 0.02))
    for g in (p.mesh.g0, lie.exp([0.3, -0.2, 0.5, 0.4, 0.2, -0.7]) @ p.mesh.g0):    # reference, rigidly moved
        K = p.tangent(g, 0.0).toarray()
        N = rigid_body_modes(g, p.length_scale).reshape(-1, 6)
        scale = np.abs(K).max() * np.abs(N).max()
        assert np.abs(K @ N).max() < 1e-10 * scale
        # the other sign of the rotational modes' translation (x cross e) is not a null vector
        bad = N.copy().reshape(-1, 6, 6)
        bad[:, :3, 3:] = -bad[:, :3, 3:] + 0.0
        bad = bad.reshape(-1, 6)
        assert np.abs(K @ bad[:, 3:]).max() > 1e-3 * scale
        assert np.linalg.matrix_rank(N) == 6


def test_a_serial_run_imports_no_mpi():
    code = ("import sys, core_se3; from core_se3 import Problem, Material, mesh; "
            "p = Problem(mesh.rectangle(1.0, 1.0, 4, 1), Material(1e3, 0.0, 0.01)); p.clamp('x0'); "
            "p.add_edge_force('x1', (0, 0, 1e-3)); p.solve(steps=1); "
            "print('mpi4py' in sys.modules, 'petsc4py' in sys.modules)")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI", "SLURM"))}
    env["PYTHONPATH"] = ROOT
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["False", "False"], out.stderr


def test_front_door_mpirun_core_se3_run(tmp_path):
    """``mpirun -n 2 core-se3 run FILE.toml``: rank 0 writes the run directory, the answers are
    the serial run's."""
    if not HAVE_MPI:
        pytest.skip("needs mpi4py, petsc4py and mpirun")
    from core_se3 import scenario
    toml = tmp_path / "strip.toml"
    toml.write_text('name = "strip"\n[mesh]\ngenerator = "rectangle"\nL = 10.0\nwidth = 1.0\nnx = 16\nny = 2\n'
                    '[material]\nE = 1.2e6\nnu = 0.0\nh = 0.1\n[[supports]]\ntype = "clamp"\nedge = "x0"\n'
                    '[[loads]]\ntype = "edge_force"\nedge = "x1"\nforce = [0.0, 0.0, 4.0]\n'
                    '[[probes]]\nname = "tip"\nedge = "x1"\n[solver]\nsteps = 4\nlinear = "mumps"\n'
                    '[output]\nplots = false\npicture = false\n')
    cmd = ["mpirun", "-n", "2", "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS",
           sys.executable, "-m", "core_se3", "run", str(toml), "--out", str(tmp_path / "out")]
    p = subprocess.run(cmd, env=mpi_env(), capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    assert p.stdout.count("strip: 4 steps") == 1                       # rank 0 alone reports
    doc = json.loads((tmp_path / "out" / "results.json").read_text())
    ser = scenario.run(scenario.load(str(toml)), out=str(tmp_path / "serial"))
    assert doc["status"] == "complete"
    assert [s["iterations"] for s in doc["steps"]] == [s["iterations"] for s in ser.doc["steps"]]
    u, v = doc["steps"][-1]["probes"]["tip"]["u"], ser.doc["steps"][-1]["probes"]["tip"]["u"]
    assert np.linalg.norm(np.subtract(u, v)) < 1e-10 * np.linalg.norm(v)
    assert len(list((tmp_path / "out" / "vtu").glob("step_*.vtu"))) == 5


@pytest.mark.parametrize("name", DESIGNS)
def test_a_design_on_two_ranks_reaches_the_serial_design(two_ranks, name):
    """A design under mpirun: its equilibria (Newton tries on the ranks' shares) and its
    sensitivities (distributed transpose or direct solves with MUMPS) give the optimiser what the
    serial run gives it, to the round-off of a different linear solver: the same designed value
    to 1e-9 relative (measured: tip angle identical, field direction 2.9e-12; the least-squares
    optimiser stops at gtol 1e-12), the target reached, iterations and solves within one."""
    from core_se3.catalogue import run_case
    ser = run_case(name)[0]["design"]
    par = two_ranks[name]
    assert par["reached"] and ser["reached"]
    for k, v in ser["variables"].items():
        assert abs(par["variables"][k] / v - 1) < 1e-9, (k, par["variables"][k], v)
    assert abs(par["iterations"] - ser["iterations"]) <= 1
    assert abs(par["equilibrium_solves"] - ser["equilibrium_solves"]) <= 1


def test_a_design_with_material_variables_under_mpirun_is_refused(monkeypatch):
    """A material variable changes the element, which every rank builds once for its share: a
    design with one stops under mpirun with a ParallelError saying to run it without mpirun."""
    from core_se3.design import Design, MaterialVariable, Pose, ProbePosition, Target
    p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e4, 0.0, 0.02))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1e-3))
    p.add_probe("tip", "x1")
    reach = Pose("reach", [Target(ProbePosition(p, "tip", target=(1.0, 0.1, 0.05)))])
    d = Design(p, [MaterialVariable(p, [np.arange(4)], "E")], [reach])
    assert d.distributed is None                          # serially: no distributed run
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    with pytest.raises(ParallelError, match="material variable.*without mpirun"):
        d.distributed


# ------------------------------------------------------------ one rank's error, every rank's ------
class _TwoRanks:
    """Rank ``rank`` of two, the other rank's word given: what ``allgather`` and ``bcast`` are sent
    is kept (the other ranks wait in them)."""
    size = 2

    def __init__(self, rank=0, other=None):
        self.rank, self.other, self.sent = rank, other, []

    def allgather(self, value):
        self.sent.append(value)
        return [value, self.other] if self.rank == 0 else [self.other, value]

    def bcast(self, value, root=0):
        self.sent.append(value)
        return value if self.rank == root else self.other


def test_an_error_of_any_type_on_one_rank_reaches_every_rank():
    """A load of one's own that fails with an IndexError on the rank that holds none of its nodes
    (``self.nodes[0]``): ``collective`` caught only core_se3, ValueError and arithmetic errors, so
    that rank left alone and the others waited in the next allgather forever (measured: mpirun -n 2
    killed by its 60 s timeout); now the error goes to the allgather and every rank raises it."""
    from core_se3.parallel import collective
    comm = _TwoRanks(rank=0)

    def fails():
        return np.zeros(0, int)[0]
    with pytest.raises(IndexError):
        collective(comm, fails)
    assert comm.sent and comm.sent[0][0] is IndexError           # the other ranks learn of it
    other = _TwoRanks(rank=1, other=(IndexError, "index 0 is out of bounds"))
    with pytest.raises(IndexError, match="out of bounds"):
        collective(other, lambda: 1.0)


def test_rank_zeros_output_error_reaches_every_rank(monkeypatch):
    """``scenario.context.on_root`` (rank 0 claims the run directory, checks the checkpoint):
    an OSError there (an output path under a file, a full disk) stayed on rank 0, and the other
    ranks waited for its broadcast forever (``mpirun -n 2 core-se3 run s.toml --out FILE/sub``
    printed the error and hung until its timeout); now it is broadcast and raised on every rank."""
    import core_se3.parallel
    from core_se3.scenario import context
    monkeypatch.setattr(context, "launched_ranks", lambda: 2)
    root = _TwoRanks(rank=0)
    monkeypatch.setattr(core_se3.parallel, "world", lambda: root)

    def claim():
        raise NotADirectoryError(20, "Not a directory", "/tmp/file/sub")
    with pytest.raises(NotADirectoryError):
        context.on_root(claim)
    assert root.sent and root.sent[0][0][0] is NotADirectoryError
    other = _TwoRanks(rank=1, other=((NotADirectoryError, "[Errno 20] Not a directory"), None))
    monkeypatch.setattr(core_se3.parallel, "world", lambda: other)
    with pytest.raises(NotADirectoryError, match="Not a directory"):
        context.on_root(claim)


FULL_DISK = '''
import errno, sys
from core_se3 import scenario
from core_se3.scenario import sinks
from core_se3.parallel import world
sys.path.insert(0, {here!r})
from parallel_cases import scenario_dict
rank, real, calls = world().rank, sinks.write_json_atomic, []
def full(path, doc, *a, **k):                 # rank 0's disk fills up at the results of step 2
    calls.append(path)
    if rank == 0 and len(calls) == 3:
        raise OSError(errno.ENOSPC, "No space left on device", path)
    return real(path, doc, *a, **k)
sinks.write_json_atomic = full
try:
    scenario.run(scenario.from_dict(scenario_dict()), out={out!r})
except OSError as exc:
    open({out!r} + ".rank%d" % rank, "w").write(str(exc))
'''


def test_a_full_disk_on_rank_zero_stops_every_rank(tmp_path):
    """Rank 0 writes the run's files; an OSError there (a full disk at step 2's results.json) left
    the other ranks in the next Newton step's collectives and rank 0 in the failed run's last
    VTU gather: mpirun hung (killed by a 60 s timeout).  Now every write of rank 0 tells the
    others its outcome: both ranks stop with the error within seconds, and results.json says
    'failed' with the message and the steps converged before it."""
    if not HAVE_MPI:
        pytest.skip("needs mpi4py, petsc4py and mpirun")
    script = tmp_path / "full.py"
    script.write_text(FULL_DISK.format(here=HERE, out=str(tmp_path / "out")))
    cmd = ["mpirun", "-n", "2", "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS",
           sys.executable, str(script)]
    p = subprocess.run(cmd, env=mpi_env(), capture_output=True, text=True, timeout=240, cwd=ROOT)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    for rank in (0, 1):                                              # each rank's error
        assert "No space left on device" in (tmp_path / f"out.rank{rank}").read_text()
    doc = json.loads((tmp_path / "out" / "results.json").read_text())
    assert doc["status"] == "failed" and "No space left on device" in doc["error"]
    assert [s["step"] for s in doc["steps"]] == [0, 1]


def test_a_ranks_contact_messages_name_the_whole_meshs_nodes_and_elements():
    """A rank's part of a contact load numbers its nodes locally; its refusals named those local
    ids: the ball rising under a strip, 'starts the increment 0.457 inside the shell at node 4'
    on two ranks where the serial run says node 13.  Now the rank's part names the whole mesh's
    nodes (and the elements of its faces), as the serial load does."""
    p = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(1e6, 0.0, 0.1))
    p.clamp("x0")
    whole = p.add_obstacle("sphere", centre=(8.0, 0.0, -1.1), radius=1.0, motion=dict(translate=(0, 0, 1e4)),
                           name="ball")
    g, lam = p.mesh.g0, 1.2207e-4                        # the ball 1.22 up: into the strip near x = 8
    serial = whole.start_error(g, lam)
    assert "inside the shell at node 13 " in serial
    part = rcb(p.mesh.X[p.mesh.quads].mean(1), 2)
    subs = [subdomain(p.mesh, part, rank, 2) for rank in range(2)]
    parts = [localize_load(whole, sub)[0] for sub in subs]
    assert serial in [loc.start_error(g[sub.nodes], lam) for sub, loc in zip(subs, parts)]
    for sub, loc in zip(subs, parts):                   # the faces' elements: the rank's, by their mesh ids
        assert np.array_equal(sub.elements[loc._quad_el], loc.face_ids)


def test_a_sweep_under_mpirun_is_refused_before_it_writes(monkeypatch, tmp_path):
    """``mpirun -n 2 core-se3 sweep``: every rank claimed the same directory and rank 1 stopped
    with 'is in use by another live run' (its sibling, rank 0), mpirun aborted, sweep.json stayed
    'running' with no row.  A sweep runs its points in one process: a ParallelError on every rank
    says so before anything is written."""
    from core_se3 import scenario
    from parallel_cases import scenario_dict
    scn = scenario.from_dict(scenario_dict())
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    with pytest.raises(ParallelError, match="sweep runs its grid points .* without mpirun"):
        scenario.sweep(scn, {"material.E": [1.2e6, 2.4e6]}, out=str(tmp_path / "sw"), plot=False)
    assert not (tmp_path / "sw").exists()


def test_the_scenario_warnings_are_printed_once_under_mpirun(monkeypatch, capsys):
    """``mpirun -n 2 core-se3 run`` printed each scenario warning (a load number above 1000) once
    per rank on stderr; rank 0 prints them now, as it prints the rest of the run's report."""
    from core_se3 import scenario
    from core_se3.cli.scenario import _preamble
    from parallel_cases import scenario_dict
    spec = scenario_dict()
    spec["loads"] = [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 4.0e4]}]
    scn = scenario.from_dict(spec)
    assert any("above 1000" in str(w) for w in scn.warnings)
    said = []
    for rank in ("0", "1"):
        monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
        monkeypatch.setenv("OMPI_COMM_WORLD_RANK", rank)
        _preamble(scn, quiet=True)
        said.append(capsys.readouterr().err)
    assert "above 1000" in said[0] and said[1] == ""


SUB_COMMUNICATORS = '''
import json, sys
import numpy as np
from mpi4py import MPI
from core_se3 import Problem, Material, mesh
from core_se3.parallel import RunSetup, distributed_solve
w = MPI.COMM_WORLD
p = Problem(mesh.rectangle(10.0, 1.0, 8, 2), Material(1.2e6, 0.3, 0.1))
p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0 + w.rank % 2))      # each group its own load
ser = p.solve(steps=2, solver="serial")
out = {{}}
for name, comm in (("self", MPI.COMM_SELF), ("halves", w.Split(w.rank % 2, w.rank))):
    try:
        res = distributed_solve(p, steps=2, setup=RunSetup(comm=comm), inertia_check=True)
        out[name] = [float(np.abs(res.final.g - ser.final.g).max()), res.parallel["ranks"]]
    except Exception as exc:
        out[name] = [type(exc).__name__ + ": " + str(exc), None]
open({out!r} + ".%d" % w.rank, "w").write(json.dumps(out))
'''


def test_a_run_on_a_sub_communicator(tmp_path):
    """``RunSetup(comm=...)``: the PETSc objects were made on PETSc.COMM_WORLD whatever the run's
    communicator, so a run of its own on every rank (``MPI.COMM_SELF``) stopped with petsc4py's
    'A matrix with 81 rows requires a row pointer of length 82 (given: 163)', and 4 ranks split
    into two runs of 2 with 'the tangent of the unloaded shell is singular -- a rigid-body
    motion is not restrained' (both wrong).  Now PETSc works on the run's ranks: each rank's
    (each half's) run gives its own serial state to round-off, with MUMPS' inertia count on."""
    if not HAVE_MPI:
        pytest.skip("needs mpi4py, petsc4py and mpirun")
    script = tmp_path / "sub.py"
    out = str(tmp_path / "out")
    script.write_text(SUB_COMMUNICATORS.format(out=out))
    cmd = ["mpirun", "-n", "4", "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS",
           sys.executable, str(script)]
    p = subprocess.run(cmd, env=mpi_env(), capture_output=True, text=True, timeout=240, cwd=ROOT)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    for rank in range(4):
        got = json.loads(open(f"{out}.{rank}").read())
        assert got["self"][1] == 1 and got["self"][0] < 1e-10, got
        assert got["halves"][1] == 2 and got["halves"][0] < 1e-10, got


def test_the_final_state_warnings_are_printed_once_under_mpirun(monkeypatch):
    """``mpirun -n 2`` printed Problem.solve's SupportWarning (a held dof that drifted) and the
    dipole MeshWarning once per rank (the same final state on every rank).  Rank 0 prints them now;
    the others warn unprinted, so that ``-W error`` stops every rank, not rank 0 alone (a hang)."""
    import warnings
    from core_se3.errors import SupportWarning
    from core_se3.model.solving import check_held_dofs
    p = Problem(mesh.rectangle(1.0, 0.5, 2, 1), Material(1e4, 0.3, 0.05))
    p.fix("x0", (0, 1, 2, 4))                       # the root's rotation about d2 held by fix: it drifts
    p.add_lab_support("x1", [[0.0, 0.0, 1.0]], 1e6)
    p.add_edge_moment("x1", (0.1, 0.0, 0.2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = p.solve(steps=1)
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    shown = {}
    for rank in ("0", "1"):
        monkeypatch.setenv("OMPI_COMM_WORLD_RANK", rank)
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            warnings.showwarning = lambda message, *args, **kw: shown.setdefault(rank, []).append(str(message))
            check_held_dofs(p, res)
        with warnings.catch_warnings():
            warnings.simplefilter("error", SupportWarning)
            with pytest.raises(SupportWarning, match="drifted by"):
                check_held_dofs(p, res)
    assert len(shown["0"]) == 1 and "drifted by" in shown["0"][0] and "1" not in shown


_CRITICAL_RUN = '''
import json, sys, warnings
from core_se3 import scenario
scn = scenario.from_dict(dict(
    mesh=dict(generator="rectangle", L=10.0, width=1.0, nx=10, ny=1), material=dict(E=1.2e6, nu=0.0, h=0.1),
    supports=[dict(type="clamp", edge="x0")], loads=[dict(type="edge_force", edge="x1", force=[-4.0, 0.0, 0.0])],
    solver=dict(steps=4, limit_check=False), output=dict(vtu=False, plots=False, picture=False)))
warnings.simplefilter("ignore")
whole = scenario.run(scn, out=sys.argv[1] + "/whole")
try:
    scenario.run(scn, out=sys.argv[1] + "/cut", stop_after=2)
except scenario.RunInterrupted:
    pass
scenario.run(scn, out=sys.argv[1] + "/cut", resume=True)
'''


@pytest.mark.parametrize("ranks", [0, 2])
def test_a_distributed_load_control_writes_the_serial_critical_points(tmp_path, ranks):
    """The compressed strip as a scenario (limit_check = false, 4 steps) on two ranks, whole and
    interrupted after step 2 then resumed: results.json's critical_points (the bifurcation passed
    between 0.5 and 0.75, Euler ~0.617, at stored step 3, with its description) are the serial
    run's, and its provenance says the steps were solved distributed."""
    if ranks and not HAVE_MPI:
        pytest.skip("needs mpi4py, petsc4py and mpirun")
    script = tmp_path / "run.py"
    script.write_text(_CRITICAL_RUN)
    cmd = [sys.executable, str(script), str(tmp_path)]
    if ranks:
        cmd = ["mpirun", "-n", str(ranks), "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS"] + cmd
    p = subprocess.run(cmd, env=mpi_env(), capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    docs = [json.loads((tmp_path / d / "results.json").read_text()) for d in ("whole", "cut")]
    for doc in docs:
        (cp,) = doc["critical_points"]
        assert cp["kind"] == "bifurcation" and cp["bracket"] == [0.5, 0.75] and cp["step"] == 3
        assert cp["accuracy"] is None and "not located" in cp["description"]
        assert doc["provenance"]["solve"] == ("distributed" if ranks else "serial")
    assert docs[0]["critical_points"] == docs[1]["critical_points"]
