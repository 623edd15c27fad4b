"""The registry of solvers by control (``Problem.solve`` looks them up; ``core_se3.solvers`` and
``core_se3.parallel`` fill it, so the model layer does not depend on them) and the choice
between the serial solvers and the distributed one.

Example
-------
>>> sorted(SOLVERS)
['arclength', 'displacement', 'distributed', 'linear', 'load']
"""
from __future__ import annotations

import warnings
from typing import Callable

import numpy as np

from ..backend import launched_rank, launched_ranks
from ..errors import MeshWarning, OptionError, ParallelError, SupportWarning, did_you_mean
from .prescribed import DOF_NAMES, DRIFT_TOL, held_dof_drift

__all__ = ["SOLVERS", "LINEAR_SOLVERS", "check_linear_solver", "DISTRIBUTED_KEYS", "dispatch", "solve_linear",
           "check_held_dofs", "warn_final_state", "dipole_warning"]

# keywords of the distributed set-up (a scenario's [solver] linear, petsc, partition), which
# the serial solvers do not take
DISTRIBUTED_KEYS = ("linear", "petsc_options", "partition")

SOLVERS: dict[str, Callable] = {}
"""Solvers by control name ('load', 'arclength', 'displacement', 'linear'): solve(problem, **options); and
'distributed' (load stepping over MPI ranks, ``core_se3.parallel``)."""

LINEAR_SOLVERS: dict[str, Callable] = {}
"""The linear solvers by name (a Problem's ``linear_solver``): a function giving None where the
solver runs on this machine, else why not; filled by ``core_se3.solvers``."""


def check_linear_solver(name):
    """``name`` if it is a linear solver (:data:`LINEAR_SOLVERS`) that runs on this machine, else
    an :class:`~core_se3.errors.OptionError` naming the choices that do: ``Problem(linear_solver=
    "lu")``, or ``"mumps"`` without petsc4py, was refused only when a solve began.

    Example
    -------
    >>> check_linear_solver("superlu")
    'superlu'
    >>> check_linear_solver("lu")          # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: Problem: unknown linear_solver 'lu'; the choices on this machine: auto, banded, ...
    """
    if not LINEAR_SOLVERS:                   # (core_se3.solvers not imported: checked when it solves)
        return name
    why = LINEAR_SOLVERS[name]() if isinstance(name, str) and name in LINEAR_SOLVERS else "unknown"
    if why is None:
        return name
    here = ", ".join(sorted(k for k, usable in LINEAR_SOLVERS.items() if usable() is None))
    if why == "unknown":
        raise OptionError(f"Problem: unknown linear_solver {name!r}"
                          f"{did_you_mean(name, LINEAR_SOLVERS) if isinstance(name, str) else ''}; "
                          f"the choices on this machine: {here}")
    raise OptionError(f"Problem: linear_solver {name!r} {why}; the choices on this machine: {here}")


def dispatch(problem, control, solver, kw, given=()):
    """Solve ``problem`` with the solver of ``control``: the distributed one for load control
    with ``solver="distributed"``, or by default when launched among several MPI ranks
    (``backend.launched_ranks``); the serial one otherwise.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem.
    control : str
        'load', 'arclength' or 'displacement'.
    solver : str or None
        None, 'serial' or 'distributed'.
    kw : dict
        The solver's keywords; the distributed set-up's (``linear``, ``petsc_options``,
        ``partition``, or ``setup``: a ``parallel.RunSetup``) go to the distributed solver as
        its ``setup`` and are dropped for a serial solver.
    given : iterable of str, optional
        The keys of ``kw`` that the call gave (not a problem's ``solve_defaults``): those the
        solver takes and does not use (its ``unused_options``, e.g. ``steps`` of a linear
        analysis) give an :class:`~core_se3.errors.OptionWarning`.

    Returns
    -------
    core_se3.Result

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> dispatch(p, "load", "parallel", {})
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown solver 'parallel'; choose 'serial' or 'distributed'
    """
    kw = dict(kw)
    kw.pop("solver", None)
    controls = [c for c in SOLVERS if c != "distributed"]
    if control not in controls:
        raise OptionError(f"unknown control {control!r}{did_you_mean(control, controls)}; "
                          f"choose one of {', '.join(sorted(controls))}")
    if solver not in (None, "serial", "distributed"):
        raise OptionError(f"unknown solver {solver!r}; choose 'serial' or 'distributed'")
    if solver == "distributed" and control != "load":
        raise ParallelError(f"the distributed solver steps the load (control='load'); control "
                            f"{control!r} runs serially (drop solver='distributed')")
    if solver == "distributed" or (solver is None and control == "load" and launched_ranks() > 1):
        given = {k: kw.pop(k) for k in DISTRIBUTED_KEYS if k in kw}
        if given and kw.get("setup") is not None:
            raise OptionError(f"the distributed set-up given twice, as setup= and as {', '.join(given)}=: give one")
        if given:
            kw["setup"] = given           # parallel.RunSetup's fields
        return check_held_dofs(problem, SOLVERS["distributed"](problem, **kw))
    for k in DISTRIBUTED_KEYS + ("setup",):
        kw.pop(k, None)
    unused = getattr(SOLVERS[control], "unused_options", None)
    if unused is not None:      # the solver warns of those the call gave; solve_defaults' are dropped quietly
        kw = {k: v for k, v in kw.items() if k in given or unused({k: v}) is None}
    problem.check_element(stacklevel=4)    # the coarse-mesh warning, supports known (the distributed set-up's own)
    return check_held_dofs(problem, SOLVERS[control](problem, **kw))


def check_held_dofs(problem, result):
    """``result``, after the warnings of its final state (:func:`warn_final_state`)."""
    states = [s for s in getattr(result, "steps", []) if getattr(s, "g", None) is not None]
    if states:
        warn_final_state(problem, states[-1], stacklevel=5)     # Problem.solve's caller
    return result


def warn_final_state(problem, state, stacklevel=2):
    """The warnings of a final state (``Problem.solve``, a scenario run): a
    :class:`~core_se3.errors.SupportWarning` if a support let a dof it holds drift more than
    ``DRIFT_TOL`` (``prescribed.held_dof_drift``): it holds the body-frame components of each
    increment while its nodes turn about other axes, so it is not holonomic and the state depends
    on the load steps at that order (measured on the Sze et al. semicylinder's edges, u_z and the
    rotation about y held with ``fix``: 4.9e-4 rad of drift, 3.3e-6 rad between 1 and 160 load
    steps); a MeshWarning for a point dipole too close to the magnet (``_check_dipole_resolution``).
    ``state``: .g and .load_factor.  Under an MPI launch every rank warns (``-W error`` stops
    them all) and rank 0 alone prints (:func:`_warn`)."""
    worst = held_dof_drift(problem.supports, problem.mesh.g0, state.g)
    if worst is not None and worst[0] > DRIFT_TOL:
        drift, k, node, dof = worst
        amount = f"{drift:.2g} rad" if dof >= 3 else f"{drift:.2g} of the largest displacement"
        _warn(SupportWarning(
            f"support {k} holds the {DOF_NAMES[dof]} of its nodes in the turning body frame (fix), "
            f"and its nodes turn about other axes: the held component drifted by {amount} (node "
            f"{node}), so the state depends on the load steps at that order. For an exact, path-"
            f"independent support hold the lab component: add_lab_support (translations) or "
            f"add_rotation_component_support (a rotation-vector component), in a scenario file "
            f'[[supports]] type = "lab" (a direction) or type = "lab_rotation" (an axis); or clamp.'), stacklevel)
    _check_dipole_resolution(problem, state, stacklevel + 1)


def _warn(warning, stacklevel):
    """warnings.warn(warning) from ``stacklevel`` frames above the caller; on ranks other than 0
    of an MPI launch (the same state on every rank) not printed, but still raised under ``-W
    error`` (every rank then stops, none waits for another)."""
    if launched_rank() == 0:
        warnings.warn(warning, stacklevel=stacklevel + 1)
        return
    with warnings.catch_warnings():          # the filters kept (an error stays an error)
        warnings.showwarning = lambda *args, **kw: None
        warnings.warn(warning, stacklevel=stacklevel + 1)


def _check_dipole_resolution(problem, state, stacklevel):
    """A MeshWarning when a point dipole lies within ``magnetics.DIPOLE_RESOLUTION`` element sizes
    of the magnetised material at the final state (:func:`dipole_warning`)."""
    from .magnetics import MagneticLoad
    mags = [ld for ld in problem.loads if isinstance(ld, MagneticLoad)]
    warning = dipole_warning(mags, state.g, state.load_factor) if mags else None
    if warning is not None:
        _warn(warning, stacklevel)


def dipole_warning(loads, g, lam):
    """The MeshWarning of a state g at load factor lam whose magnetised material lies within
    ``magnetics.DIPOLE_RESOLUTION`` element sizes of a point dipole of the MagneticLoads
    ``loads``, else None: the nodal quadrature of the dipole's loads is then off by about
    (size / distance)^2, and refining along one direction only can converge to a wrong answer
    (``DIPOLE_RESOLUTION``'s measurements).  ``Problem.solve`` warns with it at its final state,
    a control session (``control.Session``) at every state that comes within that distance.

    Example
    -------
    >>> from core_se3 import mesh
    >>> from core_se3.model import MagneticLoad, Magnetisation, DipoleField
    >>> m = mesh.rectangle(1.0, 0.1, 10, 1)
    >>> ld = MagneticLoad(Magnetisation(m, (1.0, 0, 0), h=0.01, mu0=1.0), DipoleField((0, 0, 1.0), (1.0, -0.05, 0.3)))
    >>> str(dipole_warning([ld], m.g0, 1.0))[:58]
    'the point dipole at [1.0, -0.05, 0.3] lies 3 element sizes'
    >>> dipole_warning([ld], m.g0, 0.0) is None                # scaled to zero
    True
    """
    from .magnetics import DIPOLE_RESOLUTION, dipole_resolution
    worst = dipole_resolution(loads, g, lam)
    if worst is None or worst[0] >= DIPOLE_RESOLUTION:
        return None
    ratio, node, x0 = worst
    return MeshWarning(
        f"the point dipole at {np.round(x0, 6).tolist()} lies {ratio:.3g} element sizes from the magnetised "
        f"node {node} (fewer than {DIPOLE_RESOLUTION:g}): its field changes across an element, and the nodal "
        f"quadrature of the magnetic couple and force is off by about (size / distance)^2 = "
        f"{100 / ratio ** 2:.2g} %; refine the mesh near the dipole in both directions (to "
        f"{DIPOLE_RESOLUTION:g} sizes: 1 %) or move the dipole away")


def solve_linear(problem, lam_end=1.0, **options):
    """Linear analysis (``Problem.solve_linear``): one solve at the reference state
    (``solvers.linear_solve``), the loads at ``lam_end`` on the reference geometry; a Result like
    ``Problem.solve``'s (the reference state and the linear solution).  Same as
    ``problem.solve(control="linear")``.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (4e-4, 0.0, 0.0)); p.add_probe("tip")
    >>> round(float(p.solve_linear().final.probes["tip"]["u"][0] / (4e-4 * 10.0 / 1.2e5)), 6)  # P L/(E A)
    1.0
    """
    return problem.solve(control="linear", lam_end=lam_end, **options)
