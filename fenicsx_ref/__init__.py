"""fenicsx_ref: an independent UFL/DOLFINx total-Lagrangian Naghdi director shell.

It shares nothing with ``core_se3`` but the declarative case definitions
(``core_se3.catalogue``) and the reference data.  DOLFINx is imported lazily, on the first
``run_case`` call, so that ``python -m fenicsx_ref bench list`` works without it.

    >>> from fenicsx_ref import run_case
    >>> r = run_case("cantilever-shear", mesh=(16, 1), integration="psri")
    >>> r["reference"]["error"]
"""
__all__ = ["run_case", "JIT_CACHE_DIR"]

import os as _os

#: where the FFCx/CFFI JIT cache lives (override with FENICSX_REF_JIT_CACHE); see README.md
JIT_CACHE_DIR = _os.environ.get(
    "FENICSX_REF_JIT_CACHE", _os.path.join(_os.path.expanduser("~"), ".cache", "fenicsx_ref", "jit"))


def run_case(name, mesh=None, overrides=None, steps=None, integration="psri", shear_factor=1.0, **kw):
    """Solve a case of ``core_se3.cases``; see :func:`fenicsx_ref.solver.run_case`."""
    from .solver import run_case as _run
    return _run(name, mesh=mesh, overrides=overrides, steps=steps, integration=integration,
                shear_factor=shear_factor, **kw)
