"""Run by tests/test_parallel.py under ``mpirun -n 2`` (and ``-n 1``): the agreement cases with the
distributed solver, and a scenario run interrupted and resumed; rank 0 writes the outcome as JSON.

    mpirun -n 2 python tests/parallel_driver.py OUT.json [case ...] [design-...] [sandwich-...] [fuzz-144-...] [counts] [first-step-buckling] [roof-counts] [resume]
"""
import json
import os
import sys
import tempfile

import numpy as np

from core_se3.errors import ConvergenceError, SingularSystemError
from core_se3.parallel import world

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from parallel_cases import CASES, FAILS, ONE_SIDED, PROBES, STOPS, build, roof_on_symmetry_planes, scenario_dict  # noqa: E402


def summary(res):
    return dict(iterations=[int(s.iterations) for s in res.steps], attempts=[s.attempts for s in res.steps[1:]],
                checks=[s.checks for s in res.steps[1:]],
                critical_points=[dict(kind=cp.kind, step=cp.step, lam_bracket=list(cp.lam_bracket),
                                      node=getattr(cp, "node", None), travel=getattr(cp, "travel", None))
                                 for cp in res.critical_points],
                lam=[float(s.load_factor) for s in res.steps],
                probes=[{k: np.asarray(v["u"]).tolist() for k, v in s.probes.items()} for s in res.steps],
                contact=[{k: np.asarray(v["force"]).tolist() for k, v in (s.contact or {}).items()} for s in res.steps],
                g=np.asarray(res.final.g).ravel()[::7].tolist())


def main(out, names):
    comm = world()
    doc = {"ranks": comm.size}
    for name in [n for n in names if n.startswith("design-")]:      # a design's optimiser on the ranks
        from core_se3.catalogue import run_case
        doc_d, _, _ = run_case(name)
        d = doc_d["design"]
        doc[name] = dict(variables=d["variables"], max_misfit=d["max_misfit"], reached=d["reached"],
                         iterations=d["iterations"], equilibrium_solves=d["equilibrium_solves"])
    for name in [n for n in names if n in CASES or n in ONE_SIDED]:
        prob, steps, kw = build(name)
        if comm.size == 1:                           # one rank: the shared-matrix path, asked for
            kw = dict(kw, solver="distributed")
        res = prob.solve(steps=steps, **kw)          # dispatches to the distributed solver
        doc[name] = summary(res)
        doc[name]["parallel"] = {k: v for k, v in res.parallel.items() if k in ("ranks", "linear")}
    for name in [n for n in names if n in STOPS or n in PROBES or n in FAILS or n == "sandwich-stable"]:   # runs the checks stop
        prob, steps, kw = build(name)
        try:
            res = prob.solve(steps=steps, solver="distributed", **kw)
            doc[name] = dict(message=None, lam=[float(s.load_factor) for s in res.steps],
                             critical_points=len(res.critical_points))
        except ConvergenceError as exc:
            doc[name] = dict(message=str(exc), lam=[float(s.load_factor) for s in exc.result.steps])
    if "first-step-buckling" in names:    # a first load step onto the start tangent's singular load
        from test_step_checks import _first_step_on_buckling_load
        try:
            _first_step_on_buckling_load().solve(steps=2, solver="distributed")
            doc["first-step-buckling"] = None
        except (ConvergenceError, SingularSystemError) as exc:
            res = getattr(exc, "result", None)
            doc["first-step-buckling"] = dict(error=type(exc).__name__, message=str(exc),
                                              lam=None if res is None else [float(s.load_factor) for s in res.steps])
    if "roof-counts" in names:       # the ranks' counts on a shell held on symmetry planes (serial states)
        from core_se3.parallel import DistributedRun
        for follower in (False, True):
            prob = roof_on_symmetry_planes(follower)
            ser = prob.solve(steps=4, solver="serial")
            run = DistributedRun(prob, comm)
            doc["roof-counts" + "-follower" * follower] = [run.negative_count(s.g, s.load_factor) for s in ser.steps]
            run.close()
    if "counts" in names:            # the ranks' inertia count at the serial states of the sandwich strip
        from core_se3.parallel import DistributedRun
        prob, _, _ = build("sandwich-5")
        ser = prob.solve(steps=5, solver="serial", end_check=False, limit_check=False)
        run = DistributedRun(prob, comm)
        doc["counts"] = [run.negative_count(s.g, s.load_factor) for s in ser.steps]
        run.close()
    if "resume" in names or not names:
        from core_se3 import scenario
        scn = scenario.from_dict(scenario_dict())
        base = tempfile.mkdtemp() if comm.rank == 0 else None
        base = comm.bcast(base)
        whole = scenario.run(scn, out=os.path.join(base, "whole"))
        try:
            scenario.run(scn, out=os.path.join(base, "cut"), stop_after=2)
        except scenario.RunInterrupted:
            pass
        resumed = scenario.run(scn, out=os.path.join(base, "cut"), resume=True)
        doc["resume"] = dict(difference=float(np.abs(np.asarray(whole.g) - np.asarray(resumed.g)).max()
                                              / np.abs(np.asarray(whole.g)).max()),
                             steps=len(resumed.doc["steps"]),
                             files=sorted(os.listdir(os.path.join(base, "whole"))),
                             vtu=sorted(os.listdir(os.path.join(base, "whole", "vtu"))))
    if comm.rank == 0:
        with open(out, "w") as fh:
            json.dump(doc, fh)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
