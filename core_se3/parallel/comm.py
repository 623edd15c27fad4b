"""The communicator of a distributed run and the collective forms of the few decisions that a
rank could otherwise take alone (an error on one rank becomes the same error on every rank, so
no rank waits in a collective that another has left).

mpi4py is imported by :func:`world` only, never at module level: a serial run does not load MPI.
"""
from __future__ import annotations

import numpy as np

from ..backend import launched_ranks
from ..errors import CoreSE3Error, ParallelError

__all__ = ["SerialComm", "world", "collective", "is_root", "petsc_comm"]


class SerialComm:
    """The one-rank communicator of a serial run (the mpi4py calls this package uses).

    Example
    -------
    >>> c = SerialComm()
    >>> c.rank, c.size, c.allreduce(3.0), c.allgather("a"), c.bcast(5)
    (0, 1, 3.0, ['a'], 5)
    """
    rank = 0
    size = 1

    def allreduce(self, value, op=None):
        return value

    def allgather(self, value):
        return [value]

    def bcast(self, value, root=0):
        return value

    def gather(self, value, root=0):
        return [value]

    def Barrier(self):
        return None

    barrier = Barrier


def world():
    """mpi4py's COMM_WORLD when the process was launched among several ranks (imported here,
    once), else a :class:`SerialComm`.

    Returns
    -------
    mpi4py.MPI.Comm or SerialComm
        ParallelError when a launcher started several ranks but mpi4py is missing.

    Example
    -------
    >>> world().size >= 1
    True
    """
    if launched_ranks() == 1:
        return SerialComm()
    try:
        from mpi4py import MPI
    except ImportError as exc:
        raise ParallelError(f"this process runs under an MPI launcher but mpi4py does not import ({exc}); "
                            "install python3-mpi4py (Debian) or run without mpirun") from None
    return MPI.COMM_WORLD


def petsc_comm(comm):
    """The PETSc communicator of a run on ``comm``: the mpi4py communicator itself (petsc4py takes
    it: a sub-communicator, e.g. ``MPI.COMM_SELF`` for a run of its own on every rank), or
    ``PETSc.COMM_SELF`` for a :class:`SerialComm` (a process that no launcher started among others).

    Example
    -------
    >>> import importlib.util
    >>> petsc_comm(SerialComm()).getSize() if importlib.util.find_spec("petsc4py") else 1
    1
    """
    from petsc4py import PETSc
    return PETSc.COMM_SELF if isinstance(comm, SerialComm) else PETSc.Comm(comm)


def is_root(comm=None):
    """True on rank 0 (the rank that writes files and logs).

    Example
    -------
    >>> is_root(SerialComm())
    True
    """
    return (comm or world()).rank == 0




def collective(comm, fn, *args, **kw):
    """Run ``fn(*args, **kw)`` on every rank; if it raised on any rank, raise on every rank the
    exception of the lowest such rank (its type and message; a ConvergenceError keeps no result).

    Parameters
    ----------
    comm : mpi4py.MPI.Comm or SerialComm
        The ranks that take part.
    fn : callable
        The local work.

    Returns
    -------
    object
        fn's value on this rank.

    Example
    -------
    >>> collective(SerialComm(), lambda x: 2 * x, 21)
    42
    >>> collective(SerialComm(), np.log, -1.0) if False else "no error on any rank"
    'no error on any rank'
    """
    err, out = None, None
    try:
        out = fn(*args, **kw)
    except Exception as exc:           # any error one rank meets alone (an IndexError of a load of one's own too)
        err = exc
    if comm.size == 1:
        if err is not None:
            raise err
        return out
    flags = comm.allgather(None if err is None else (type(err), str(err)))
    first = next((i for i, f in enumerate(flags) if f is not None), None)
    if first is not None:
        if first == comm.rank:
            raise err
        cls, msg = flags[first]
        try:
            exc = cls(msg)
        except Exception:                       # an exception type with another signature
            exc = CoreSE3Error(msg)
        raise exc
    return out
