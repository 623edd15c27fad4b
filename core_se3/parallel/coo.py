"""PETSc's COO assembly (``MatSetPreallocationCOO`` once, ``MatSetValuesCOO`` per iteration) for a
petsc4py that does not wrap it (3.18): the two C functions of the loaded libpetsc, called
through ctypes on the Mat's handle.  Off-process entries are allowed: PETSc sends them to the
owner of their row and sums repeated entries.

petsc4py is imported inside the functions only.
"""
from __future__ import annotations

import ctypes
import glob
import os

import numpy as np

from ..errors import ParallelError

__all__ = ["petsc_library", "CooMatrix"]

_LIB = []


def petsc_library():
    """The libpetsc that petsc4py loaded, as a ctypes library with the two COO functions typed.

    Returns
    -------
    ctypes.CDLL
        ParallelError when it cannot be found or lacks the COO functions (PETSc < 3.15).

    Example
    -------
    >>> import importlib.util
    >>> petsc_library().MatSetValuesCOO is not None if importlib.util.find_spec("petsc4py") else True
    True
    """
    if _LIB:
        return _LIB[0]
    import petsc4py
    from petsc4py import PETSc  # noqa: F401  (loads libpetsc into the process)
    paths = []
    try:
        with open("/proc/self/maps") as fh:
            paths = sorted({ln.split()[-1] for ln in fh if "libpetsc" in ln and ln.split()[-1].startswith("/")})
    except OSError:
        pass
    if not paths:
        paths = sorted(glob.glob(os.path.join(petsc4py.get_config()["PETSC_DIR"], "lib", "libpetsc*.so*")))
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
            lib.MatSetPreallocationCOO.argtypes = [ctypes.c_void_p, ctypes.c_int64, ctypes.c_void_p,
                                                   ctypes.c_void_p]
            lib.MatSetValuesCOO.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int]
            lib.MatSetPreallocationCOO.restype = lib.MatSetValuesCOO.restype = ctypes.c_int
        except (OSError, AttributeError):
            continue
        _LIB.append(lib)
        return lib
    raise ParallelError("cannot find libpetsc with MatSetPreallocationCOO (PETSc >= 3.15 is needed)")


class CooMatrix:
    """A distributed AIJ matrix filled through COO: ``rows``/``cols`` (global indices) fixed
    once, ``set(values)`` per iteration (repeated entries and entries of other ranks' rows
    are summed; the matrix is assembled afterwards).

    Parameters
    ----------
    comm : petsc4py.PETSc.Comm
        The ranks.
    n_local, n_global : int
        Rows (and columns) owned here, and in all.
    rows, cols : (k,) array_like of int
        The global (row, column) of every value this rank contributes.
    bsize : int, optional
        The block size (6 for shell nodes; the multigrid solvers read it).

    Example
    -------
    >>> import importlib.util, numpy as np
    >>> if importlib.util.find_spec("petsc4py"):
    ...     from petsc4py import PETSc
    ...     A = CooMatrix(PETSc.COMM_SELF, 2, 2, [0, 1, 0], [0, 1, 0])
    ...     _ = A.set(np.array([1.0, 2.0, 3.0]))
    ...     print(A.mat.getValue(0, 0), A.mat.getValue(1, 1))
    ... else:
    ...     print(4.0, 2.0)
    4.0 2.0
    """

    def __init__(self, comm, n_local, n_global, rows, cols, bsize=1):
        from petsc4py import PETSc
        self.PETSc = PETSc
        self.lib = petsc_library()
        A = PETSc.Mat().create(comm)
        A.setSizes(((n_local, n_global), (n_local, n_global)), bsize=bsize)
        A.setType(PETSc.Mat.Type.AIJ)
        rows = np.ascontiguousarray(rows, dtype=PETSc.IntType).copy()     # PETSc may reorder them
        cols = np.ascontiguousarray(cols, dtype=PETSc.IntType).copy()
        self.n = len(rows)
        err = self.lib.MatSetPreallocationCOO(A.handle, self.n, rows.ctypes.data, cols.ctypes.data)
        if err:
            raise ParallelError(f"MatSetPreallocationCOO failed (PETSc error {err})")
        self.mat = A

    def set(self, values):
        """Replace the matrix by the sums of ``values`` (k,) at the COO positions; returns the Mat."""
        v = np.ascontiguousarray(values, dtype=self.PETSc.ScalarType)
        if v.shape != (self.n,):
            raise ParallelError(f"CooMatrix.set needs {self.n} values, got {v.shape}")
        err = self.lib.MatSetValuesCOO(self.mat.handle, v.ctypes.data, 1)          # INSERT_VALUES
        if err:
            raise ParallelError(f"MatSetValuesCOO failed (PETSc error {err})")
        return self.mat

    def destroy(self):
        self.mat.destroy()
