"""Run checkpoints: the state after the last converged load step, written atomically (files.py).

A checkpoint (``checkpoint.npz``) holds what a run needs to continue exactly where it stopped:
the nodal frames g (n, 4, 4) of the last converged step, its load factor and step number, the
continuously unwrapped probe rotation vectors, the step records written so far (results
JSON), the accumulated timings, and the fingerprint of the scenario it belongs to; an
arc-length run adds its follower state (``extra["arc"]``, scalars, and ``arrays``: the
previous increment, a pending switch mode).  The array fields are optional, so files written
before them still load (version 1 either way).  Resuming
from it repeats the same per-step Newton solves from the same bits, so the final state equals
that of an uninterrupted run.
"""
from __future__ import annotations

import json
import os

import numpy as np

from ..errors import CheckpointError
from .files import atomic_path

__all__ = ["Checkpoint"]

FORMAT = "core-se3-checkpoint"
VERSION = 1
_ARRAY = "array_"                  # prefix of the optional named arrays (save(arrays=...))


class Checkpoint:
    """The checkpoint file of a run directory.

    ``save(fingerprint, state)`` writes the state (a dict: step, lam, g, unwrap, records,
    timings, optionally extra and arrays) atomically; ``load(fingerprint=None)`` returns it as
    such a dict (with its fingerprint) and raises
    :class:`~core_se3.errors.CheckpointError` if it is missing, unreadable or, when a fingerprint
    is given, of another scenario; ``exists()`` tells whether there is one.

    Parameters
    ----------
    directory : str or path-like
        The run directory; the file is ``directory/checkpoint.npz``.

    Example
    -------
    >>> import tempfile, numpy as np
    >>> ck = Checkpoint(tempfile.mkdtemp())
    >>> ck.save("fp", dict(step=1, lam=0.5, g=np.eye(4)[None], unwrap={}, records=[], timings={}))
    >>> ck.load("fp")["lam"]
    0.5
    >>> ck.load("another scenario")                # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.CheckpointError: checkpoint ... belongs to a different scenario ...
    """

    def __init__(self, directory):
        self.directory = os.fspath(directory)
        self.path = os.path.join(self.directory, "checkpoint.npz")

    def exists(self):
        return os.path.isfile(self.path)

    def save(self, fingerprint, state):
        """Write ``state`` atomically under ``fingerprint``: a dict with step, lam, g (n, 4, 4),
        unwrap ({probe: (3,)}), records (JSON-able list), timings (JSON-able dict) and optionally
        extra (JSON-able dict) and arrays ({name: float array}): what :meth:`load` returns (its
        own fingerprint key is not read)."""
        step, lam, g, unwrap = state["step"], state["lam"], state["g"], state["unwrap"]
        records, timings = state["records"], state["timings"]
        extra, arrays = state.get("extra"), state.get("arrays")
        names = sorted(unwrap)
        arrs = {_ARRAY + k: np.asarray(v, float) for k, v in (arrays or {}).items()}
        with atomic_path(self.path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, format=np.array(FORMAT), version=np.array(VERSION),
                         fingerprint=np.array(fingerprint), step=np.array(int(step)),
                         lam=np.array(float(lam)), g=np.asarray(g, float),
                         probe_names=np.array(json.dumps(names)),
                         unwrap=np.array([unwrap[k] for k in names], float).reshape(len(names), 3),
                         records=np.array(json.dumps(records)), timings=np.array(json.dumps(timings)),
                         extra=np.array(json.dumps(extra or {})), **arrs)

    def load(self, fingerprint=None):
        """The saved state as a dict; CheckpointError if missing, unreadable or foreign."""
        if not self.exists():
            raise CheckpointError(f"no checkpoint to resume from: {self.path} does not exist "
                                  "(run without --resume first)")
        try:
            with np.load(self.path, allow_pickle=False) as z:
                if str(z["format"]) != FORMAT or int(z["version"]) != VERSION:
                    raise ValueError(f"not a {FORMAT} v{VERSION} file")
                names = json.loads(str(z["probe_names"]))
                state = dict(fingerprint=str(z["fingerprint"]), step=int(z["step"]),
                             lam=float(z["lam"]), g=np.array(z["g"]),
                             unwrap={k: np.array(w) for k, w in zip(names, z["unwrap"])},
                             records=json.loads(str(z["records"])),
                             timings=json.loads(str(z["timings"])),
                             extra=json.loads(str(z["extra"])),
                             arrays={k[len(_ARRAY):]: np.array(z[k]) for k in z.files
                                     if k.startswith(_ARRAY)})
        except Exception as exc:
            raise CheckpointError(f"cannot read checkpoint {self.path}: {exc} (a damaged or cut-short file, or not "
                                  "a checkpoint of core-se3); the run's other files are kept: run without --resume "
                                  "(and with --force) to start over, or use another --out") from None
        if fingerprint is not None and state["fingerprint"] != fingerprint:
            raise CheckpointError(
                f"checkpoint {self.path} belongs to a different scenario (the mesh, material, "
                "supports, loads, fields, probes, steps or element changed since it was written); "
                "run without --resume (and with --force) to start over, or use another --out")
        return state
