"""The computational backend: 'numba' (compiled kernels, ``core_se3.kernels``), 'numpy' (the
batched NumPy reference) or 'auto' (NumPy until numba pays for itself, then numba; below).  The
default is 'auto' when numba is installed, else 'numpy'; the environment variable
``CORE_SE3_BACKEND`` overrides it, ``set_backend`` changes it for the problems created
afterwards, and ``Problem(..., backend=...)`` chooses per problem.

The 'auto' rule is the ski-rental rule.  Starting numba costs a fixed time per process (its
import and its first cache loads, about 0.3-0.45 s on the 2-core test machine with a warm cache;
benchmarks/results/speed.md), which a small scene never earns back: a 16-element cantilever
solves in 40 Newton iterations, where numba saves about 1.2 ms each.  So every process starts on
NumPy and, after each tangent evaluation, adds up what numba would have saved
(:func:`iteration_saving`, a fit of the measured per-iteration assembly of both backends); once
that reaches the start cost, the process switches to numba for good (the problem's next
evaluation).  The total is then at most about twice the better of the two fixed choices, for any
sequence of solves: one short run pays no numba start, a sweep or design loop of hundreds of
solves runs on numba after its first few.  The rule counts work, not time, so a script takes the
same path in every run with the same kernel cache state -- a cold cache raises the start cost
(:data:`NUMBA_COLD_START_COST`) and so moves the switch later, and the two backends differ by
round-off, which a long design loop can carry into a different iterate within its tolerance
(the gripper design example, measured: misfit 6.4e-5 mm on NumPy, 1.9e-2 on numba, 5.6e-3 on
'auto', tolerance 2e-2).  For runs to repeat bit for bit across machines and caches, fix the
backend (``CORE_SE3_BACKEND=numba``).  A distributed run (``launched_ranks() > 1``) takes
numba at once.

Example
-------
>>> from core_se3 import backend
>>> backend.resolve("numpy")
'numpy'
>>> backend.resolve("fortran")
Traceback (most recent call last):
...
core_se3.errors.OptionError: unknown backend 'fortran'; choose 'auto', 'numba' or 'numpy'
"""
from __future__ import annotations

import functools
import importlib.util
import os

from .errors import OptionError

__all__ = ["BACKENDS", "numba_available", "default_backend", "set_backend", "resolve", "active",
           "charge", "iteration_saving", "NUMBA_START_COST", "rent_state", "restore_rent",
           "pin_for_timing", "launched_ranks", "launched_rank", "start_cost", "kernel_cache_warm",
           "mark_kernel_cache_warm", "NUMBA_COLD_START_COST"]

BACKENDS = ("auto", "numba", "numpy")
_chosen = None

# The ski-rental rule of 'auto' (module docstring), fitted to benchmarks/results/speed.md of
# 2026-12-03 (2-core x86_64, one thread; per Newton iteration, residual checks included): NumPy
# minus numba assembly 1.15 ms at 16 elements, 3.05 ms at 120, 8.2 ms at 256, 56 ms at 2304,
# 203 ms at 10^4; numba's start on the same host 0.31-0.45 s (speed.md's main job, peers.md).
NUMBA_START_COST = 0.4        # s: numba's import and first cache loads
SAVING_PER_ITERATION = 0.9e-3  # s
SAVING_PER_ELEMENT = 1.8e-5    # s per element and iteration


# numba's start with a cold cache: it compiles the kernels first; measured with an empty
# NUMBA_CACHE_DIR on the 2-core test machine: a cantilever with one edge force (the element
# kernels and one load) 22.4 s of CPU, ``core-se3 warmup`` (every kernel) 31.9 s
NUMBA_COLD_START_COST = 22.0  # s
WARM_MARKER = "warm.json"      # written into the kernels' cache directory by ``core-se3 warmup``


class _Rent:
    """What 'auto' has spent on NumPy so far in this process (estimated saving of numba, s), and
    whether the kernels' cache was cold when it started counting (None: not looked at yet)."""
    saved = 0.0
    switched = False
    cold = None


def iteration_saving(n_elements):
    """The time [s] numba's kernels save over NumPy in one Newton iteration (the tangent and the
    residual checks) of a mesh of ``n_elements`` elements: the fit above.

    Example
    -------
    >>> from core_se3.backend import iteration_saving
    >>> round(iteration_saving(16) * 1e3, 2)          # ms
    1.19
    """
    return SAVING_PER_ITERATION + SAVING_PER_ELEMENT * float(n_elements)


def start_cost():
    """numba's start cost [s] for the 'auto' rule: ``NUMBA_START_COST`` with a warm kernel cache,
    ``NUMBA_COLD_START_COST`` when the kernels would be compiled first (looked at once per
    process and kept in the rule's count, so that a resumed run uses the same)."""
    if _Rent.cold is None:
        _Rent.cold = numba_available() and not kernel_cache_warm()
    return NUMBA_COLD_START_COST if _Rent.cold else NUMBA_START_COST


def charge(n_elements, share=1.0):
    """Count one NumPy tangent evaluation of an 'auto' problem of ``n_elements`` elements (or
    ``share`` of one: a control session's residual-only evaluations, ``control.corrector``):
    once the savings missed reach :func:`start_cost`, 'auto' means numba from then on (with a
    cold cache, after a one-line notice on stderr of the compilation about to start)."""
    if not _Rent.switched:
        _Rent.saved += share * iteration_saving(n_elements)
        if _Rent.saved >= start_cost():
            _Rent.switched = True
            if _Rent.cold:
                import sys
                print(f"core_se3: the 'auto' backend moves to numba now and compiles its kernels first, once "
                      f"(about {NUMBA_COLD_START_COST:.0f} s; `core-se3 warmup` does it ahead)", file=sys.stderr,
                      flush=True)


def _cache_paths():
    """``kernels/cache.py`` (the kernels' cache directory) loaded on its own: the kernels package
    imports numba, which this module must not."""
    import importlib.util
    spec = importlib.util.spec_from_file_location(
        "core_se3._kernel_cache_paths", os.path.join(os.path.dirname(os.path.abspath(__file__)), "kernels", "cache.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def kernel_cache_warm():
    """True when the cache of the kernels' current source holds the compiled element kernels
    (nine tenths of the compile time; a load's kernel compiles in under a second): filled by
    ``core-se3 warmup`` (its marker) or by an earlier run.

    Example
    -------
    >>> kernel_cache_warm() in (True, False)
    True
    """
    import glob
    d = _cache_paths().cache_directory()
    return os.path.exists(os.path.join(d, WARM_MARKER)) or all(
        glob.glob(os.path.join(glob.escape(d), f"element.element_{k}_serial-*.nbi")) for k in ("residual", "tangent"))


def mark_kernel_cache_warm(seconds=None):
    """Write the marker of a filled kernel cache (``core-se3 warmup``); returns the directory."""
    import json
    d = _cache_paths().cache_directory()
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, WARM_MARKER), "w") as fh:
        json.dump({"seconds": seconds}, fh)
    _Rent.cold = False
    return d


def rent_state():
    """The 'auto' rule's count of this process (JSON-able): a checkpoint keeps it, so that a
    resumed run switches to numba where the uninterrupted run did (bit-for-bit resume)."""
    return {"saved": _Rent.saved, "switched": _Rent.switched, "cold": _Rent.cold}


def restore_rent(state):
    """Set the 'auto' count from :func:`rent_state`'s dict (None: leave it).

    Example
    -------
    >>> from core_se3 import backend
    >>> old = backend.rent_state()
    >>> backend.restore_rent({"saved": 0.1, "switched": False}); backend.rent_state()["saved"]
    0.1
    >>> backend.restore_rent(old)
    """
    if state:
        _Rent.saved, _Rent.switched = float(state["saved"]), bool(state["switched"])
        _Rent.cold = state.get("cold")


def active(name):
    """The backend that evaluates now for the setting ``name`` ('auto', 'numba' or 'numpy'):
    'auto' is 'numpy' until :func:`charge` has counted enough work, or numba is missing, and
    'numba' after (or at once in a distributed run).

    Example
    -------
    >>> from core_se3 import backend
    >>> backend.active("numpy")
    'numpy'
    """
    if name != "auto":
        return name
    if not numba_available():
        return "numpy"
    if _Rent.switched or launched_ranks() > 1:
        return "numba"
    return "numpy"


@functools.lru_cache(maxsize=None)
def numba_available():
    """True when numba can be imported (without importing it; looked up once per process)."""
    return importlib.util.find_spec("numba") is not None


def default_backend():
    """The backend new problems use: set_backend's, else $CORE_SE3_BACKEND, else 'auto' if numba
    is installed, else 'numpy'."""
    if _chosen is not None:
        return _chosen
    env = os.environ.get("CORE_SE3_BACKEND", "").strip().lower()
    if env:
        return resolve(env)
    return "auto" if numba_available() else "numpy"


def pin_for_timing(environ=None):
    """Fix ``CORE_SE3_BACKEND`` to 'numba' (or 'numpy' without numba) unless it is set, in
    ``environ`` (default ``os.environ``: this process and the processes it starts).  For timing
    studies (``benchmarks/``, ``python -m comparison``): they time the compiled product, not
    the NumPy start of 'auto', which depends on what the process solved before.  Returns the
    backend now set.

    Example
    -------
    >>> from core_se3.backend import pin_for_timing
    >>> pin_for_timing({"CORE_SE3_BACKEND": "numpy"})
    'numpy'
    """
    env = os.environ if environ is None else environ
    env.setdefault("CORE_SE3_BACKEND", "numba" if numba_available() else "numpy")
    return env["CORE_SE3_BACKEND"]


def set_backend(name):
    """Set the backend of the problems created from now on (None: back to the default rule)."""
    global _chosen
    _chosen = None if name is None else resolve(name)


def resolve(name):
    """A validated backend name (None: the default)."""
    if name is None:
        return default_backend()
    if name not in BACKENDS:
        raise OptionError(f"unknown backend {name!r}; choose 'auto', 'numba' or 'numpy'")
    if name == "numba" and not numba_available():
        raise OptionError("the numba backend needs numba (pip install numba); use backend='numpy'")
    return name


# environment variables in which MPI launchers announce the number of processes of the job
_RANK_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS", "SLURM_STEP_NUM_TASKS")


def launched_ranks(environ=None):
    """The number of MPI processes this one was started among, read from the launcher's
    environment (Open MPI's ``OMPI_COMM_WORLD_SIZE``, MPICH/Hydra's ``PMI_SIZE``, PMIx's, Slurm's
    ``SLURM_STEP_NUM_TASKS`` under ``srun``), without importing mpi4py; 1 outside a launcher.

    ``Problem.solve`` hands load control to the distributed solver (``core_se3.parallel``)
    when this is above 1, so a serial run never imports mpi4py or petsc4py.

    Parameters
    ----------
    environ : mapping, optional
        The environment to read (default ``os.environ``).

    Returns
    -------
    int
        >= 1.

    Example
    -------
    >>> launched_ranks({}), launched_ranks({"OMPI_COMM_WORLD_SIZE": "4"})
    (1, 4)
    """
    env = os.environ if environ is None else environ
    for name in _RANK_VARIABLES:
        value = env.get(name, "").strip()
        if value.isdigit() and int(value) > 0:
            return int(value)
    return 1


_RANK_ID_VARIABLES = ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK", "SLURM_PROCID")


def launched_rank(environ=None):
    """This process's rank among those of its MPI launcher (0 outside one), from the
    environment as :func:`launched_ranks` (rank 0 writes the files of a run).

    Example
    -------
    >>> launched_rank({}), launched_rank({"OMPI_COMM_WORLD_RANK": "1", "OMPI_COMM_WORLD_SIZE": "2"})
    (0, 1)
    """
    env = os.environ if environ is None else environ
    if launched_ranks(env) == 1:
        return 0
    for name in _RANK_ID_VARIABLES:
        value = env.get(name, "").strip()
        if value.isdigit():
            return int(value)
    return 0
