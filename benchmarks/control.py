"""Control sessions at control rates (issue 32): warm updates per second on the gripper and on
finer gripper meshes, for small and large field changes, with both backends, against one LU
factorisation and solve of the same tangent timed in the same run, and the updated states
against cold solves.  Writes benchmarks/results/control.md (and .json).

    python benchmarks/control.py                  # the gripper, 4x and 16x the elements (~3 min)
    python benchmarks/control.py --meshes 1 4     # the gripper and 4x the elements only

The gripper is examples/gripper.toml (the cross mesh.cross(20, 6, 8, 3): 105 quads, 768 free
dofs); the finer meshes are the same cross with 2x and 4x the elements along and across each
arm (4x and 16x the elements), the same physics built in Python (checked against the scenario's
own problem on the coarse mesh).  Commands are field vectors B = B0 (1 + r tri(k)) with a
triangle wave tri stepping by 1 per update: r = 1e-3 ("small": 0.06 mT per update) and r = 5e-2
("large": 3 mT per update, between 60 and 90 mT and back).

Each update is timed, and after it one LU factorisation and solve of the tangent at the start
state: SciPy's ``splu`` with its defaults (COLAMD, the "SciPy LU" of the issue) and the
project's own equilibrated factorisation (``solvers.Factorization``, the 'auto' choice: LAPACK's
banded LU on the gripper, SuperLU or MUMPS on the finer meshes), each on the CSR/CSC matrix
ready (conversion not timed).  Ratios are of medians of these interleaved timings, so that the
load of the machine falls on both alike; in brackets the same ratio of process CPU times
(``time.process_time``: what the machine's other work inflates less), and beside the updates
per second of wall time those per second of the process's CPU time (what one core of its own
would give).  The factorisations per update include the renewals of aged factors and of
stale ones (``control.corrector``: the ski-rental rule with a factorisation priced at 6
iterations; stale factors renewed at the predicted state).  Accuracy: the largest over nodes of
the position difference / ell and of the rotation angle between the updated state and a cold
solve (load stepping from the flat state to rtol = dtol = 1e-12) at the same command, at the
middle and the last command of each sequence.  Everything runs on one thread
(``NUMBA_NUM_THREADS`` = ``OPENBLAS_NUM_THREADS`` = 1 unless set): the ratios compare work on
one core.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

# one thread for everything (numba's kernels, OpenBLAS under MUMPS): the ratios then compare work
# on one core, whatever number of cores the machine's other load leaves (set these to change it)
for _var in ("NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)

from core_se3 import Material, Problem, lie, mesh, scenario  # noqa: E402
from core_se3.control import Session  # noqa: E402
from core_se3.design import FieldVariable  # noqa: E402
from core_se3.model import MU0, UniformField  # noqa: E402
from core_se3.solvers import Factorization, make_solver  # noqa: E402

GRIPPER = os.path.join(ROOT, "examples", "gripper.toml")
C = 0.004808326112068524                   # |Br| cos 45 deg = 6.8 mT / sqrt(2), as gripper.toml
FINGERS = {"finger_px": (C, 0.0, -C), "finger_mx": (-C, 0.0, -C), "finger_py": (0.0, C, -C),
           "finger_my": (0.0, -C, -C)}


def gripper_problem(refine, backend):
    """examples/gripper.toml's problem on mesh.cross(20, 6, 8 refine, 3 refine)."""
    if refine == 1:
        scn = scenario.load(GRIPPER)
        p = scn.problem
        p.backend = backend
        return p, scn.fields["coil"]
    p = Problem(mesh.cross(20.0, 6.0, 8 * refine, 3 * refine), Material(E=0.4698783, nu=0.45, h=0.7),
                backend=backend)
    p.clamp(p.mesh.node_set("palm"))
    field = UniformField((0.0, 0.0, 0.06))
    for region, br in FINGERS.items():
        p.add_magnetic(br, field, elements=region, mu0=MU0 * 1e6)
    p.add_probe("tip_px", "tip_px")
    p.add_probe("tip_py", "tip_py")
    return p, field


def check_python_build():
    """The Python build on the scenario's mesh equals the scenario (same cold solution)."""
    a, _ = gripper_problem(1, "numba")
    p = Problem(a.mesh, Material(E=0.4698783, nu=0.45, h=0.7), backend="numba")
    p.clamp(p.mesh.node_set("palm"))
    f = UniformField((0.0, 0.0, 0.06))
    for region, br in FINGERS.items():
        p.add_magnetic(br, f, elements=region, mu0=MU0 * 1e6)
    ga, gb = (q.solve(steps=12, rtol=1e-12, dtol=1e-12).final.g for q in (a, p))
    err = np.abs(ga - gb).max()
    assert err < 1e-9, f"the Python gripper differs from the scenario's by {err:g}"
    return err


def frame_error(g, h, ell):
    dx = np.abs(g[:, :3, 3] - h[:, :3, 3]).max() / ell
    dw = np.abs(lie.log_so3(np.swapaxes(g[:, :3, :3], 1, 2) @ h[:, :3, :3])).max()
    return float(max(dx, dw))


def triangle(k, n_up):
    """0, 1, ..., n_up, n_up - 1, ..., -n_up, ...: steps of 1."""
    period = 4 * n_up
    k = k % period
    return k if k <= n_up else (2 * n_up - k if k <= 3 * n_up else k - 4 * n_up)


def run_sequence(s, B0, r, n, n_up, K, b, solver, checks):
    """n updates B0 (1 + r tri(k)), each followed by one splu and one Factorization of K."""
    rows = dict(update=[], splu=[], own=[], update_cpu=[], splu_cpu=[], own_cpu=[], iterations=[],
                factorizations=[], substeps=[], errors=[])
    p, ell = s.problem, s.problem.length_scale
    Kc = K.tocsc()

    def timed(key, fn):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        rows[key].append(time.perf_counter() - t)
        rows[key + "_cpu"].append(time.process_time() - c)
        return out

    def own():
        with Factorization(K, solver) as F:
            F.solve(b)

    for k in range(1, n + 1):
        B = B0 * (1.0 + r * triangle(k, n_up))
        st = timed("update", lambda: s.update(coil=B))
        timed("splu", lambda: spla.splu(Kc).solve(b))
        timed("own", own)
        rows["iterations"].append(st.iterations)
        rows["factorizations"].append(st.factorizations)
        rows["substeps"].append(st.substeps)
        if k in checks:
            g = st.g
            f = s.variables["coil"]
            cold = p.solve(steps=12, lam_end=1.0, rtol=1e-12, dtol=1e-12).final.g
            assert np.allclose(f.value(), B)
            rows["errors"].append(frame_error(g, cold, ell))
    return rows


def case(refine, backend, n_small, n_large):
    p, field = gripper_problem(refine, backend)
    t = time.perf_counter()
    s = Session(p, 1.0, [FieldVariable(p, field, name="coil")], steps=12)
    t_start = time.perf_counter() - t
    B0 = s.values["coil"].copy()
    ev = p.evaluate(s.g, 1.0, tangent=True)
    K, b = ev.K, -ev.r + 1.0
    solver = make_solver("auto")
    which = solver.choice(K)
    for k in range(3):                              # warm: kernels, caches, the solver's layout
        s.update(coil=B0 * (1 + 1e-4 * (k + 1)))
        spla.splu(K.tocsc()).solve(b)
        with Factorization(K, solver) as F:
            F.solve(b)
    s.update(coil=B0)
    out = dict(refine=refine, backend=backend, nodes=p.mesh.n_nodes, elements=p.mesh.n_elements,
               dofs=int(p.assembler().nfree), solver=which, start=t_start)
    # the jacobian of the two tips by the field at the start, on the held factors
    s.jacobian(["tip_px", "tip_py"], ["coil"])
    tj = []
    for _ in range(5):
        t = time.perf_counter()
        s.jacobian(["tip_px", "tip_py"], ["coil"])
        tj.append(time.perf_counter() - t)
    out["jacobian"] = float(np.median(tj))
    # the old way: Problem.solve one step from the converged state (the 13.5 ms)
    told = []
    g0 = s.g
    for k in range(5):
        field.B = B0 * (1 + 1e-3 * (k + 1))
        t = time.perf_counter()
        p.solve(steps=1, lam_start=1.0, lam_end=1.0 + 1e-12, g_init=g0)
        told.append(time.perf_counter() - t)
    field.B = B0.copy()
    out["solve_step"] = float(np.median(told))
    for label, r, n, n_up in (("small", 1e-3, n_small, 10), ("large", 5e-2, n_large, 6)):
        checks = {n // 2, n}
        rows = run_sequence(s, B0, r, n, n_up, K, b, solver, checks)
        s.update(coil=B0)
        med = {k: float(np.median(v)) for k, v in rows.items()
               if k.split("_")[0] in ("update", "splu", "own")}
        out[label] = dict(step=r, updates=n, median=med, per_second=1.0 / med["update"],
                          per_cpu_second=1.0 / med["update_cpu"],
                          ratio_splu=med["update"] / med["splu"], ratio_own=med["update"] / med["own"],
                          cpu_ratio_splu=med["update_cpu"] / med["splu_cpu"],
                          cpu_ratio_own=med["update_cpu"] / med["own_cpu"],
                          iterations=float(np.median(rows["iterations"])),
                          factorizations=float(np.mean(rows["factorizations"])),
                          substeps=float(np.mean(rows["substeps"])), max_error=max(rows["errors"]),
                          times=rows["update"])
    s.close()
    return out


def closed_loop(backend, n=201):
    """The example's figure eight (examples/gripper_control.py) tracked by Jacobian feedback on
    the gripper: cycles per second (Jacobian + update) and the largest error."""
    from core_se3.control import track
    p, field = gripper_problem(1, backend)
    s = Session(p, 1.0, [FieldVariable(p, field, free=("x", "z"), name="coil")])
    x0 = s.state.probes["tip_px"]["x"]
    t = np.linspace(0.0, 2 * np.pi, n)
    targets = np.stack([x0[0] + 1.5 * np.sin(t), x0[2] + 0.25 * np.sin(2 * t)], 1)
    f0 = s.counts["factorizations"]
    tr = track(s, "tip_px", targets, components=[0, 2])
    return dict(backend=backend, cycles=n - 1, rate=tr.rate, max_error=tr.max_error,
                iterations=float(np.median(tr.iterations[1:])),
                factorizations=(s.counts["factorizations"] - f0) / (n - 1))


def table(results):
    lines = ["| mesh | free dofs | backend | command | updates/s (per CPU s) | median update [ms] | splu [ms] | "
             "update / splu (CPU) | own LU [ms] | update / own LU (CPU) | back-subst. | factorisations / update | "
             "max error / ell |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for o in results:
        for label in ("small", "large"):
            c = o[label]
            m = c["median"]
            lines.append(f"| {o['elements']} quads | {o['dofs']} | {o['backend']} | {label} "
                         f"({100 * c['step']:g} %) | {c['per_second']:.0f} ({c['per_cpu_second']:.0f}) | "
                         f"{1e3 * m['update']:.2f} | "
                         f"{1e3 * m['splu']:.2f} | **{c['ratio_splu']:.2f}** ({c['cpu_ratio_splu']:.2f}) | "
                         f"{1e3 * m['own']:.2f} ({o['solver']}) | {c['ratio_own']:.2f} ({c['cpu_ratio_own']:.2f}) | "
                         f"{c['iterations']:g} | {c['factorizations']:.2f} | {c['max_error']:.1e} |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", type=int, nargs="+", default=[1, 2, 4], help="refinements of the cross (1 = gripper)")
    ap.add_argument("--backends", nargs="+", default=["numpy", "numba"])
    ap.add_argument("--small", type=int, default=40, help="small updates per case")
    ap.add_argument("--large", type=int, default=12, help="large updates per case")
    args = ap.parse_args(argv)
    err = check_python_build()
    results = []
    for refine in args.meshes:
        for backend in args.backends:
            t = time.perf_counter()
            o = case(refine, backend, args.small, args.large)
            results.append(o)
            print(f"refine {refine} {backend}: {time.perf_counter() - t:.1f} s; small "
                  f"{o['small']['ratio_splu']:.2f} x splu, large {o['large']['ratio_splu']:.2f} x splu", flush=True)
    lines = ["# Control sessions: warm updates against one LU (`python benchmarks/control.py`)", "",
             __doc__.split("\n\n", 2)[2].strip().replace("\n\n", "\n\n"), "",
             f"The Python build of the gripper equals the scenario's (cold solutions within {err:.1e}).", ""]
    lines += table(results)
    lines += ["", "Per case, in the same run: one Jacobian of the two fingertips by the field (3 x 6, on the "
              "session's factors: 3 back-substitutions) and, for comparison, the issue's baseline -- one "
              "`Problem.solve(steps=1, g_init=...)` step from the converged state after a 0.1 % field change:", "",
              "| mesh | backend | start (cold solve + factors) [s] | jacobian [ms] | Problem.solve step [ms] | "
              "small update [ms] |", "|---|---|---|---|---|---|"]
    for o in results:
        lines.append(f"| {o['elements']} quads | {o['backend']} | {o['start']:.2f} | {1e3 * o['jacobian']:.2f} | "
                     f"{1e3 * o['solve_step']:.2f} | {1e3 * o['small']['median']['update']:.2f} |")
    loops = [closed_loop(b) for b in args.backends]
    lines += ["", "The closed loop of `examples/gripper_control.py` on the gripper (the +x fingertip on a figure "
              "eight, 3 x 0.5 mm, 200 cycles of Jacobian feedback, one warm update per cycle):", "",
              "| backend | cycles/s | largest error [mm] | back-substitutions per update | factorisations per cycle "
              "(the Jacobian's included) |", "|---|---|---|---|---|"]
    for c in loops:
        lines.append(f"| {c['backend']} | {c['rate']:.0f} | {c['max_error']:.2e} | {c['iterations']:g} | "
                     f"{c['factorizations']:.2f} |")
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    with open(os.path.join(HERE, "results", "control.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(HERE, "results", "control.json"), "w") as f:
        json.dump(dict(cases=results, closed_loop=loops), f, indent=1)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
