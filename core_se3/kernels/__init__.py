"""Layer 0 (beside lie), the compiled kernels of the ``numba`` backend: scalar SE(3) algebra, the
fixed CSR pattern and its block scatter, the default element and every built-in load, on plain
arrays.  Importing this package imports numba; the rest of core_se3 imports it only when a
problem evaluates with the compiled backend (``core_se3.backend``), so a NumPy-only scene
never pays for it.  numba caches the compiled code in a directory per version of the kernels'
source (``kernels.cache``).  The NumPy implementation of each kernel stays the reference
(``tests/test_kernels.py`` compares them).
"""
from .cache import fingerprinted_cache

# every kernel module is imported (its functions decorated) inside the fingerprinted cache, so
# that no compiled code of an earlier version of any kernel file is ever loaded (kernels.cache)
with fingerprinted_cache():
    from . import lie, loads  # noqa: F401
    from .csr import CsrMap, Pattern, Topology, add_blocks, greedy_colouring, scatter, scatter_diag
    from .element import ElementKernels

__all__ = ["Pattern", "CsrMap", "Topology", "greedy_colouring", "scatter", "scatter_diag", "add_blocks",
           "ElementKernels"]
