"""``core-se3 warmup``: compile every numba kernel once into its cache (``kernels.cache``: one
directory per version of the kernels' source), so that no run pays for the compilation and the
'auto' backend starts numba at its warm cost (``core_se3.backend``).  ``scripts/setup.sh`` runs
it after installing.

It solves small problems on the numba backend that evaluate the default element (residual,
tangent, mixed stresses) and every built-in load with kernels: dead and follower edge forces and
moments, nodal loads, dead and follower pressure, body force, gravity, magnets in uniform and
gradient fields, the lab springs, and the probes' geodesic points; then it marks the cache warm.
"""
from __future__ import annotations

import time

import numpy as np

__all__ = ["warm_kernels", "warm_problems"]


def warm_problems():
    """The small problems whose solves compile every kernel (module docstring): (problem,
    solve options) pairs."""
    from ..fem import Material
    from ..mesh import rectangle
    from ..model import GradientField, Problem, UniformField
    m = rectangle(4.0, 1.0, 4, 2)
    p = Problem(m, Material(1e4, 0.3, 0.05, rho=1.0), backend="numba")
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 0.01))
    p.add_edge_force("x1", (0.0, 0.0, 0.01), follower=True)
    p.add_edge_moment("x1", (0.0, 0.001, 0.0))
    p.add_edge_moment("x1", (0.0, 0.001, 0.0), follower=True)
    p.add_nodal_load([7], force=(0.0, 0.001, 0.0), moment=(0.0, 0.0, 1e-4))
    p.add_nodal_load([7], force=(0.0, 0.001, 0.0), follower=True)
    p.add_pressure(1e-3)
    p.add_pressure(1e-3, follower=True)
    p.add_body_force((0.0, 0.0, -1e-3))
    p.add_gravity(g=(0.0, 0.0, -0.01))
    p.add_magnetic((0.1, 0.0, 0.0), UniformField((0.0, 0.0, 1e-3)))
    p.add_magnetic((0.1, 0.0, 0.0), GradientField((0.0, 0.0, 1e-3), np.diag([1e-4, 0.0, -1e-4])))
    p.add_lab_support("y0", [[0.0, 1.0, 0.0]], 1e3)
    p.add_lab_tilt_support("y0", (0.0, 1.0, 0.0), 1e2)
    p.add_rotation_component_support("y1", (0.0, 0.0, 1.0), 1e2)
    p.add_probe("tip", "x1")
    q = Problem(m, Material(1e4, 0.3, 0.05), backend="numba")
    q.clamp("x0")
    q.add_edge_force("x1", (0.0, 0.0, 0.05))
    q.add_probe("tip", "x1")
    return [(p, dict(steps=2)), (p, dict(steps=1, iteration="displacement")), (q, dict(steps=1, control="arclength"))]


def warm_kernels(progress=False):
    """Compile the kernels (module docstring); returns a line saying what it did and how long it
    took (``core-se3 warmup``; tests/test_front_door_findings.py runs it in a subprocess).

    Example
    -------
    The problems it solves (each on the numba backend):

    >>> [sorted(options) for _, options in warm_problems()]
    [['steps'], ['iteration', 'steps'], ['control', 'steps']]
    """
    from ..backend import kernel_cache_warm, mark_kernel_cache_warm, numba_available
    if not numba_available():
        return "numba kernels: numba is not installed (the NumPy backend needs no compilation)"
    was = kernel_cache_warm()
    t0 = time.perf_counter()
    for prob, options in warm_problems():
        if progress:
            print(f"compiling: {options}", flush=True)
        prob.solve(**options)
    path = mark_kernel_cache_warm(time.perf_counter() - t0)
    return (f"numba kernels {'were already' if was else 'now'} compiled in {path} "
            f"({time.perf_counter() - t0:.1f} s)")
