"""The memory a scenario run will need, estimated before it runs (``core-se3 run --check``), from
the measured peak memory of serial runs against their number of free unknowns N
(``benchmarks/memory.py``, results in ``benchmarks/results/memory-*.md``: square plates of
20x20 to 160x160 elements, one load step, the 'auto' linear solver, MUMPS from 2000 unknowns):

    peak = base + a N + b N log2 N

(the N log N of a sparse factorisation with nested-dissection ordering in 2-D), fitted to within
1-4 % from 9840 to 154 560 unknowns on each backend; the estimate is the larger of the two fits
(the 'auto' backend moves to numba on large meshes).  A strip factored by the banded LU needs
less.  Under ``mpirun -n N`` the factorisation is spread over the ranks.

Example
-------
>>> from core_se3 import scenario
>>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 160, "ny": 160},
...     "material": {"E": 1e6, "nu": 0.3, "h": 0.01}, "supports": [{"type": "clamp", "edge": "x0"}]})
>>> round(estimate(scn).bytes / 2 ** 30, 1)        # measured: 1.95 GiB (numba), 1.95 GiB (numpy)
1.9
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

__all__ = ["estimate", "machine_memory", "MemoryEstimate", "FITS"]

# (base [bytes], a [bytes per unknown], b [bytes per unknown and log2 unknown]): benchmarks/memory.py
FITS = {"numpy": (106.0 * 2 ** 20, 4029.3, 508.34), "numba": (266.2 * 2 ** 20, 429.9, 638.27)}


@dataclass
class MemoryEstimate:
    """An estimate: ``bytes``, the free unknowns ``unknowns`` it rests on, and the fit used."""
    bytes: float
    unknowns: int
    backend: str

    def describe(self):
        return (f"{self.unknowns} free unknowns; fit of measured serial runs, benchmarks/memory.py, "
                f"{self.backend} backend")


def estimate(scn):
    """The peak memory [bytes] of a serial run of the scenario (module docstring).

    Parameters: scn (Scenario).  Returns: MemoryEstimate.
    """
    n = int((~scn.problem.constraint_mask()).sum())
    n_ = max(n, 2)
    best = max(((base + a * n_ + b * n_ * math.log2(n_)), name) for name, (base, a, b) in FITS.items())
    return MemoryEstimate(best[0], n, best[1])


def machine_memory():
    """This machine's physical memory [bytes] (None where the system does not tell).

    Example
    -------
    >>> (machine_memory() or 1) > 0
    True
    """
    try:
        return float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):     # pragma: no cover - not POSIX
        return None
