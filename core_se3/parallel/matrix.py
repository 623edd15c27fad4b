"""The two ways the tangent reaches PETSc.

* ``CooMatrix`` (several ranks): PETSc's COO assembly (``MatSetPreallocationCOO`` once,
  ``MatSetValuesCOO`` per iteration) for a petsc4py that does not wrap it (3.18): the two C
  functions of the loaded libpetsc, called through ctypes on the Mat's handle.  Off-process
  entries are allowed: PETSc sends them to the owner of their row and sums repeated entries.
  It keeps two 8-byte maps per entry beside PETSc's copy of the matrix (about 9 kB per
  element in all at 54 entries per row), and fills the matrix in a fraction of the element
  evaluation's time.
* ``SharedCsrMatrix`` (one rank): PETSc's SeqAIJ matrix *is* the kernels' CSR
  (``MatCreateSeqAIJWithArrays`` on the pattern's arrays: no copy, nothing to fill); the held
  dofs' rows and columns are made identity rows in place after every evaluation.

petsc4py is imported inside the functions only.
"""
from __future__ import annotations

import ctypes
import glob
import os

import numpy as np

from ..errors import ParallelError

__all__ = ["petsc_library", "CooMatrix", "SharedCsrMatrix"]

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


class SharedCsrMatrix:
    """PETSc's view of a CSR matrix of all dofs on one rank, sharing its arrays (no copy): the
    kernels write ``data`` and ``set`` turns the held dofs into identity rows and columns.

    Parameters
    ----------
    indptr, indices : arrays of PETSc's integer type
        The CSR structure (columns sorted in every row; kept by reference).
    held : (N,) bool array
        The dofs a support holds (row and column zero, diagonal one).
    bsize : int, optional
        The block size (6 for shell nodes; the multigrid solvers read it).

    Example
    -------
    >>> import importlib.util, numpy as np
    >>> if importlib.util.find_spec("petsc4py"):
    ...     A = SharedCsrMatrix(np.array([0, 2, 4], np.int32), np.array([0, 1, 0, 1], np.int32),
    ...                         np.array([False, True]))
    ...     A.data[:] = [4.0, 1.0, 1.0, 5.0]
    ...     M = A.set()
    ...     print(M.getValue(0, 0), M.getValue(0, 1), M.getValue(1, 1))
    ... else:
    ...     print(4.0, 0.0, 1.0)
    4.0 0.0 1.0
    """

    def __init__(self, indptr, indices, held, bsize=1):
        from petsc4py import PETSc
        self.PETSc = PETSc
        IT = PETSc.IntType
        if np.asarray(indptr).dtype != IT or np.asarray(indices).dtype != IT:
            raise ParallelError(f"SharedCsrMatrix needs the pattern in PETSc's integer type {np.dtype(IT)}")
        self.indptr, self.indices = indptr, indices
        self.data = np.zeros(int(indptr[-1]))
        self.n = len(self.data)
        N = len(indptr) - 1
        held = np.asarray(held, bool)
        hrows = np.flatnonzero(held)
        lens = np.diff(indptr)[hrows]
        # entries of the held rows (few: supported nodes), then of the held columns (a scan)
        first = np.cumsum(lens) - lens                         # each held row's first slot in in_rows
        in_rows = np.arange(lens.sum()) + np.repeat(indptr[hrows].astype(np.int64) - first, lens)
        row_of = np.repeat(hrows, lens)
        self.diagonal = in_rows[indices[in_rows] == row_of]
        if len(self.diagonal) != len(hrows):
            raise ParallelError("SharedCsrMatrix: a held dof has no diagonal entry in the pattern")
        self.zero = np.union1d(in_rows, np.flatnonzero(held[indices]))
        self.mat = PETSc.Mat().createAIJWithArrays((N, N), (indptr, indices, self.data), comm=PETSc.COMM_SELF)
        self.mat.setBlockSizes(bsize, bsize)     # (createAIJWithArrays ignores its bsize for SeqAIJ)
        if self.mat.getType() != PETSc.Mat.Type.SEQAIJ:
            raise ParallelError("SharedCsrMatrix is for one rank (a sequential matrix)")

    def set(self, values=None):
        """The held dofs' rows and columns made identity in ``data`` (``values``: copied into
        ``data`` first if given and not ``data`` itself); returns the Mat, its state advanced."""
        if values is not None and not np.shares_memory(values, self.data):
            self.data[:] = values
        self.data[self.zero] = 0.0
        self.data[self.diagonal] = 1.0
        self.mat.assemble()                      # PETSc learns that the values changed
        return self.mat

    def destroy(self):
        self.mat.destroy()
