"""Checks of ``--resume``: the checkpoint belongs to this scenario (else the message names the
keys that changed), it is consistent (a hand-edited or damaged file: frames of the mesh's shape,
proper rotations, its step and load factor those of its last record, records numbered from 0,
the probes' unwrapped rotations), it is of the same control, and the load factors done so far
are the first ones of the scenario's steps (so a finished run can be extended to a higher
``lam_end``); and that it was written by this package version, while what else a session may
change (Python, NumPy, MPI ranks, backend, the solver controls outside the fingerprint) is said
and recorded (``session_record``, ``check_session``)."""
from __future__ import annotations

import numpy as np

from ..errors import CheckpointError, ScenarioWarning
from ..solvers.origin import HELD

__all__ = ["changed_keys", "check_same_scenario", "check_extension", "check_checkpoint", "check_consistent",
           "session_record", "check_session"]


def changed_keys(old, new, prefix=""):
    """Dotted keys whose values differ between two nested documents (with the two values).

    Example
    -------
    >>> changed_keys({"material": {"E": 1.0, "h": 0.1}, "loads": [{"p": 1}]},
    ...              {"material": {"E": 2.0, "h": 0.1}, "loads": [{"p": 1}, {"p": 2}]})
    [('material.E', 1.0, 2.0), ('loads', '1 entries', '2 entries')]
    """
    out = []
    if isinstance(old, dict) and isinstance(new, dict):
        for k in list(old) + [k for k in new if k not in old]:
            key = f"{prefix}.{k}" if prefix else str(k)
            if k not in old or k not in new:
                out.append((key, old.get(k, "(absent)"), new.get(k, "(absent)")))
            else:
                out.extend(changed_keys(old[k], new[k], key))
    elif isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            out.append((prefix, f"{len(old)} entries", f"{len(new)} entries"))
        else:
            for i, (a, b) in enumerate(zip(old, new)):
                out.extend(changed_keys(a, b, f"{prefix}[{i}]"))
    elif old != new:
        out.append((prefix, old, new))
    return out


def _short(x):
    s = repr(x)
    return s if len(s) <= 40 else s[:37] + "..."


def check_same_scenario(path, state, scn):
    """CheckpointError unless the checkpoint's fingerprint is the scenario's; it names the
    changed keys (from the scenario content the checkpoint keeps)."""
    if state["fingerprint"] in (scn.fingerprint, getattr(scn, "named_fingerprint", None)):
        return
    old = state["extra"].get("physical")
    if old is not None and "name" in old:           # an older version's, which hashed the name too
        old = {k: x for k, x in old.items() if k != "name"}
    what = ""
    if old is not None:
        diff = changed_keys(old, scn.physical)
        if diff:
            what = ": " + "; ".join(f"{k} changed from {_short(a)} to {_short(b)}" for k, a, b in diff[:4])
            what += f" (and {len(diff) - 4} more)" if len(diff) > 4 else ""
        elif scn.mesh_digest is not None:
            what = f": the mesh file {scn.spec['mesh'].get('file')!r} changed"
    else:
        what = (" (the mesh, material, supports, loads, fields, probes, steps or element changed since "
                "it was written)")
    raise CheckpointError(f"checkpoint {path} belongs to a different scenario{what}; run without --resume "
                          "(and with --force) to start over, or use another --out")


def check_extension(path, records, lams, solver):
    """CheckpointError unless the load factors of the steps done (records after the start) are
    the first ones of ``lams``: a finished run may continue to a higher lam_end with the same
    step size, not with other steps."""
    done = [r["load_factor"] for r in records[1:]]
    if len(done) > len(lams):
        raise CheckpointError(f"checkpoint {path} holds {len(done)} steps to load factor {done[-1]:g}, more than "
                              f"the {len(lams)} steps to {lams[-1]:g} of [solver]: --resume extends a run to a "
                              "higher lam_end (keeping the step size), it cannot shorten it")
    if done and not np.allclose(done, lams[:len(done)], rtol=1e-12, atol=0):
        key = "solver.load_factors" if solver.get("load_factors") else "solver.steps"
        bad = next(i for i, (a, b) in enumerate(zip(done, lams)) if abs(a - b) > 1e-12 * abs(b))
        kept = ", ".join(f"{x:.6g}" for x in done) if len(done) <= 8 else \
            ", ".join(f"{x:.6g}" for x in done[:3]) + ", ..., " + ", ".join(f"{x:.6g}" for x in done[-2:])
        raise CheckpointError(f"checkpoint {path}: {key} (or solver.lam_end) changed: step {bad + 1} was done at "
                              f"load factor {done[bad]:.6g}, the scenario now puts it at {lams[bad]:.6g}; an "
                              "extended run must keep the steps done (raise lam_end and steps in proportion), or "
                              f"give solver.load_factors that begin with them ({kept}) and go on in the steps "
                              "wanted (smaller ones toward a limit point)")


def check_checkpoint(path, st, scn):
    """Every check of a checkpoint ``st`` (``io.Checkpoint.load``) before a resume of ``scn``:
    the same scenario, a consistent file, the same control, the steps done among the scenario's.
    CheckpointError naming what is wrong."""
    check_same_scenario(path, st, scn)
    arc = scn.solver["control"] == "arclength"
    was_arc = st["extra"].get("control") == "arclength"
    if arc and (not was_arc or "arc" not in st["extra"]):
        raise CheckpointError(f"checkpoint {path} holds no arc-length path state (written by a load-controlled run "
                              "or by a version that could not resume arc length): start over with --force or use "
                              "another --out")
    if not arc and was_arc:
        raise CheckpointError(f"checkpoint {path} is of an arc-length run; this scenario is load-controlled: start "
                              "over with --force or use another --out")
    check_consistent(path, st, scn.problem)
    if not arc:
        check_extension(path, st["records"], scn.load_factors(), scn.solver)


def check_consistent(path, st, problem):
    """CheckpointError unless the checkpoint's parts agree with each other and with the problem
    (a file edited by hand, or damaged): frames (n, 4, 4) of finite proper rigid motions for the
    mesh's n nodes, records numbered 0..step, the step and load factor those of the last record,
    the probes' unwrapped rotations 3-vectors of the problem's probes, the timings numbers.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> st = dict(g=np.zeros((5, 4, 4)), step=0, lam=0.0, records=[{"step": 0, "load_factor": 0.0}], unwrap={},
    ...           timings={})
    >>> check_consistent("ck.npz", st, p)
    Traceback (most recent call last):
    ...
    core_se3.errors.CheckpointError: checkpoint ck.npz is inconsistent: its frames g have shape (5, 4, 4), the mesh has 6 nodes (expected (6, 4, 4)); it was edited or damaged: start over with --force, or use another --out
    """
    def bad(why):
        raise CheckpointError(f"checkpoint {path} is inconsistent: {why}; it was edited or damaged: start over with "
                              "--force, or use another --out")
    n = problem.mesh.n_nodes
    g = np.asarray(st["g"])
    if g.shape != (n, 4, 4):
        bad(f"its frames g have shape {g.shape}, the mesh has {n} nodes (expected ({n}, 4, 4))")
    R = g[:, :3, :3]
    if not np.all(np.isfinite(g)) or np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() > 1e-8 \
            or np.any(np.linalg.det(R) < 0) or np.abs(g[:, 3] - [0.0, 0.0, 0.0, 1.0]).max() > 0:
        bad("its frames g are not finite proper rigid motions")
    recs = st["records"]
    if not isinstance(recs, list) or not recs or any(not isinstance(r, dict) for r in recs):
        bad("it holds no step records")
    try:
        steps = [int(r["step"]) for r in recs]
        lams = [float(r["load_factor"]) for r in recs]
    except (KeyError, TypeError, ValueError):
        bad("a step record lacks its step number or load factor")
    if steps != list(range(len(recs))):
        bad(f"its records are numbered {steps[:6]}{'...' if len(steps) > 6 else ''}, not 0, 1, 2, ...")
    if st["step"] != steps[-1]:
        bad(f"its step {st['step']} is not that of its last record ({steps[-1]})")
    if not np.isfinite(st["lam"]) or st["lam"] != lams[-1]:
        bad(f"its load factor {st['lam']!r} is not that of its last record ({lams[-1]!r})")
    solver = st["extra"].get("newton") or st["extra"].get("arc") or {}
    if "lam" in solver and solver["lam"] != st["lam"]:
        bad(f"its solver state is at load factor {solver['lam']!r}, its frames at {st['lam']!r}")
    _check_held(bad, solver, st)
    if sorted(st["unwrap"]) != sorted(problem.probes) or any(np.shape(w) != (3,) or not np.all(np.isfinite(w))
                                                             for w in st["unwrap"].values()):
        bad(f"its probe rotations ({sorted(st['unwrap'])}) are not 3-vectors of the probes {sorted(problem.probes)}")
    if not isinstance(st["timings"], dict) or any(not isinstance(v, (int, float)) for v in st["timings"].values()):
        bad("its timings are not numbers")


def _check_held(bad, solver, st):
    """``bad(why)`` unless the frames a far part's solver held (``solvers.origin.held_record``:
    its origin in the solver state, the frames among the arrays) are the checkpoint's frames g
    relative to that origin, to the bit (as the run wrote them)."""
    c, held = solver.get("origin"), st.get("arrays", {}).get(HELD)
    if c is None and held is None:
        return
    try:
        c, held = np.asarray(c, dtype=float), np.asarray(held, dtype=float)
        whole = held.copy()
        whole[..., :3, 3] += c
        same = c.shape == (3,) and whole.shape == np.shape(st["g"]) and np.array_equal(whole, st["g"])
    except (TypeError, ValueError, IndexError):
        same = False
    if not same:
        bad("its frames relative to the solver's origin (held_frames, origin) are not its frames g")


def session_record(scn, ranks):
    """What one session of a run computed with beyond its scenario's fingerprint: the package
    version, Python, NumPy, the MPI ranks, the backend setting and the solver controls a resume
    may change (``scenario.NON_PHYSICAL``: rtol, max_iter, linear_solver, ...).  A checkpoint
    keeps every session's (``sessions``, each with its ``first_step``; a sweep's ``sweep.npz``
    with its ``first_row``), results.json's (sweep.json's) provenance lists them when there was
    more than one.

    Example
    -------
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 2, "ny": 1},
    ...     "material": {"E": 1e3, "nu": 0.0, "h": 0.01}, "supports": [{"type": "clamp", "edge": "x0"}]})
    >>> rec = session_record(scn, 1)
    >>> sorted(rec), rec["controls"]["rtol"]
    (['backend', 'controls', 'numpy', 'python', 'ranks', 'version'], 1e-10)
    """
    import platform
    import sys
    from .physics import NON_PHYSICAL
    return dict(version=getattr(sys.modules.get("core_se3"), "__version__", None), python=platform.python_version(),
                numpy=np.__version__, ranks=int(ranks), backend=scn.problem.backend_setting,
                controls={k: scn.solver[k] for k in NON_PHYSICAL if k in scn.solver})


def check_session(path, sessions, now, say=True):
    """Before a resume: CheckpointError if the checkpoint's last session (``sessions``, None for
    a checkpoint written before they were kept) ran another package version -- a fix or a changed
    default would make the run's steps those of two versions, reported as one's; a
    ScenarioWarning naming what else differs from session ``now`` (``session_record``): the
    resumed steps then agree with an unbroken run to round-off (ranks, backend, NumPy) or to the
    tolerances (controls), not bit for bit (``say``: this process says it; under mpirun rank 0).

    Example
    -------
    >>> old = dict(first_step=0, version="0.1.0", ranks=1)
    >>> check_session("ck.npz", [old], dict(version="0.2.0", ranks=1))      # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.CheckpointError: checkpoint ck.npz was written by core_se3 0.1.0, this is 0.2.0: ...
    """
    if not sessions:
        return
    last = sessions[-1]
    if last.get("version") != now["version"]:
        raise CheckpointError(f"checkpoint {path} was written by core_se3 {last.get('version')}, this is "
                              f"{now['version']}: the run's steps would be those of two versions (a fix or a changed "
                              "default between them changes results), reported as this one's; resume with core_se3 "
                              f"{last.get('version')}, or start over with --force (or use another --out)")
    diff = changed_keys(*({k: x for k, x in rec.items() if k not in ("first_step", "first_row")}
                          for rec in (last, now)))
    if diff and say:
        import warnings
        what = "; ".join(f"{k} {_short(a)} -> {_short(b)}" for k, a, b in diff[:6])
        warnings.warn(ScenarioWarning(
            f"{path}: this session differs from the one that wrote the checkpoint ({what}): the steps from here on "
            "agree with an unbroken run to round-off (ranks, backend, NumPy) or to the tolerances (solver "
            "controls), not bit for bit; results.json's provenance lists both sessions"), stacklevel=4)
