"""The computational backend: 'numba' (compiled kernels, ``core_se3.kernels``) or 'numpy' (the
batched NumPy reference).  The default is 'numba' when numba is installed, else 'numpy'; the
environment variable ``CORE_SE3_BACKEND`` overrides it, ``set_backend`` changes it for the
problems created afterwards, and ``Problem(..., backend=...)`` chooses per problem.

Example
-------
>>> from core_se3 import backend
>>> backend.resolve("numpy")
'numpy'
>>> backend.resolve("fortran")
Traceback (most recent call last):
...
core_se3.errors.OptionError: unknown backend 'fortran'; choose 'numba' or 'numpy'
"""
from __future__ import annotations

import importlib.util
import os

from .errors import OptionError

__all__ = ["BACKENDS", "numba_available", "default_backend", "set_backend", "resolve", "launched_ranks", "launched_rank"]

BACKENDS = ("numba", "numpy")
_chosen = None


def numba_available():
    """True when numba can be imported (without importing it)."""
    return importlib.util.find_spec("numba") is not None


def default_backend():
    """The backend new problems use: set_backend's, else $CORE_SE3_BACKEND, else numba if installed."""
    if _chosen is not None:
        return _chosen
    env = os.environ.get("CORE_SE3_BACKEND", "").strip().lower()
    if env:
        return resolve(env)
    return "numba" if numba_available() else "numpy"


def set_backend(name):
    """Set the backend of the problems created from now on (None: back to the default rule)."""
    global _chosen
    _chosen = None if name is None else resolve(name)


def resolve(name):
    """A validated backend name (None: the default)."""
    if name is None:
        return default_backend()
    if name not in BACKENDS:
        raise OptionError(f"unknown backend {name!r}; choose 'numba' or 'numpy'")
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
