"""Checks of ``--resume``: the checkpoint belongs to this scenario (else the message names the
keys that changed), and the load factors done so far are the first ones of the scenario's steps
(so a finished run can be extended to a higher ``lam_end``)."""
from __future__ import annotations

import numpy as np

from ..errors import CheckpointError

__all__ = ["changed_keys", "check_same_scenario", "check_extension"]


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
    if state["fingerprint"] == scn.fingerprint:
        return
    old = state["extra"].get("physical")
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
        raise CheckpointError(f"checkpoint {path}: {key} (or solver.lam_end) changed: step {bad + 1} was done at "
                              f"load factor {done[bad]:.6g}, the scenario now puts it at {lams[bad]:.6g}; an "
                              "extended run must keep the steps done (raise lam_end and steps in proportion)")
