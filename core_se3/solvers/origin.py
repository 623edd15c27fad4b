"""The origin a far part's iterate is held relative to (:func:`part_origin`): used by load
stepping (``solvers.equations``) and path following (``solvers.system.ShellSystem``) alike.

A part far from the origin stores its positions to an absolute round-off eps |x0|, so the
strains of an iterate carry eps |x0| / h_e (docs/STEPS.md, "Translation invariance").
"""
from __future__ import annotations

import numpy as np

from ..model.contact_frame import relocated_contact

__all__ = ["part_origin", "mesh_origin", "frames_origin", "relocation", "far_part_hint", "restart_frames",
           "held_by", "held_record", "held_of"]

HELD = "held_frames"                 # the name of the held frames among a restart state's arrays


def part_origin(problem):
    """The translation c (3,) that load stepping subtracts from the positions of ``problem``'s
    frames (module docstring), or None: per axis the smallest reference coordinate when all of
    them lie within a factor 2 of it (then X - c is exact, Sterbenz' lemma, and a part at x0
    iterates as the same part at 0), else 0; None when a load is not ``translation_invariant``
    or no axis moves.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1, x0=1e9), Material(1.2e6, 0.0, 0.1))
    >>> p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> part_origin(p).tolist(), part_origin(Problem(mesh.rectangle(10.0, 1.0, 4, 1), p.material))
    ([1000000000.0, 0.0, 0.0], None)
    """
    if not all(getattr(ld, "translation_invariant", False) for ld in problem.loads):
        return None
    return mesh_origin(problem)


def mesh_origin(problem):
    """:func:`part_origin` of the mesh alone (whatever the loads): the translation c (3,) whose
    subtraction from its reference positions is exact, or None.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> mesh_origin(Problem(mesh.rectangle(10.0, 1.0, 4, 1, x0=1e9), Material(1.2e6, 0.0, 0.1))).tolist()
    [1000000000.0, 0.0, 0.0]
    """
    X = problem.mesh.g0[:, :3, 3]
    lo, hi = X.min(0), X.max(0)
    c = np.where((lo > 0) & (hi <= 2 * lo), lo, np.where((hi < 0) & (lo >= 2 * hi), hi, 0.0))
    return c if np.any(c != 0) else None


def relocation(problem):
    """(c, loads): the origin load stepping holds ``problem``'s iterate relative to, and the loads
    to evaluate on such frames. c = :func:`part_origin` when every load is translation
    invariant (loads None: the problem's own); else :func:`mesh_origin`, when each load that is
    not has a form in the coordinates x' = x - c (contact with an obstacle of a built-in kind,
    ``model.contact_frame.relocated_contact``, or a load's own method ``relocated(c, g0)``, g0
    the reference frames in them), loads the problem's with those in their place;
    (None, None) otherwise (the iterate is held in the problem's coordinates).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 4, 4, x0=1e6), Material(1e4, 0.3, 0.02))
    >>> _ = p.add_obstacle("sphere", centre=(1e6 + 0.4, 0.1, 0.071), radius=0.06, name="ball")
    >>> c, loads = relocation(p)
    >>> c.tolist(), loads[0].obstacle.centre.round(9).tolist()     # 1e6 + 0.4 is stored to eps 1e6
    ([1000000.0, 0.0, 0.0], [0.4, 0.1, 0.071])
    """
    c = part_origin(problem)
    if c is not None or not problem.loads:
        return c, None
    c = mesh_origin(problem)
    if c is None:
        return None, None
    g0 = problem.mesh.g0.copy()
    g0[:, :3, 3] -= c
    loads = []
    for ld in problem.loads:
        moved = _relocated(ld, c, g0)
        if moved is None:
            return None, None
        loads.append(moved)
    return c, loads


def _relocated(load, c, g0):
    """``load`` in the coordinates x' = x - c (itself when translation invariant; a load's own
    ``relocated(c, g0)``, or contact's, ``model.contact_frame.relocated_contact``), or None."""
    if getattr(load, "translation_invariant", False):
        return load
    move = getattr(load, "relocated", None)
    return move(c, g0) if callable(move) else relocated_contact(load, c, g0)


def frames_origin(problem, g, origin=None):
    """``origin`` (default :func:`mesh_origin`) when the positions of the frames ``g`` lie near
    it (within half of it on each axis it moves: a far part's frames in the problem's
    coordinates), else None (a part near the origin, or frames already relative to it).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1, x0=1e9), Material(1.2e6, 0.0, 0.1))
    >>> g = p.mesh.g0.copy(); g[:, 0, 3] -= 1e9
    >>> frames_origin(p, p.mesh.g0).tolist(), frames_origin(p, g)
    ([1000000000.0, 0.0, 0.0], None)
    """
    c = mesh_origin(problem) if origin is None else origin
    if c is None:
        return None
    x = np.asarray(g)[..., :3, 3]
    return c if np.all(np.abs(x - c) <= 0.5 * np.abs(c), where=(c != 0)) else None


def far_part_hint(problem):
    """Why Newton may stall on a part far from the origin, or "": the part lies more than 1000
    element sizes from the origin (:func:`mesh_origin`) and a load is neither
    ``translation_invariant`` nor has a form relative to the part (:func:`relocation`: a user's
    SDF, a spring to a lab point, a field that varies in space), so the iterate is held in the
    problem's coordinates, whose positions carry a round-off eps |x0| that the strains see as
    eps |x0| / h_e (a 1 x 1 plate of 0.25 elements, pressed, under a user's SDF: converged at
    1e3 from the origin, stalled at the first step at 1e4, 1e6).  Otherwise the iterate is held
    relative to the part and nothing is said.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UserSDF
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 4, 4, x0=1e6), Material(1e4, 0.3, 0.02))
    >>> _ = p.add_obstacle("sphere", centre=(1e6 + 0.4, 0.1, 0.071), radius=0.06, name="ball")
    >>> far_part_hint(p)                       # a built-in obstacle is evaluated relative to the part
    ''
    >>> _ = p.add_obstacle(UserSDF(lambda y: 1.0 - y[:, 2], lambda y: np.tile([0.0, 0.0, -1.0], (len(y), 1))),
    ...                    name="lid")
    >>> far_part_hint(p)[:60]
    'the part lies 1e+06 from the origin (4e+06 element sizes) an'
    """
    c = mesh_origin(problem)
    if c is None or relocation(problem)[0] is not None:
        return ""
    g0 = problem.mesh.g0.copy()
    g0[:, :3, 3] -= c
    fixed = [ld for ld in problem.loads if _relocated(ld, c, g0) is None]
    x = problem.mesh.X[problem.mesh.edge_nodes]
    h = float(np.median(np.linalg.norm(x[:, 1] - x[:, 0], axis=1))) or problem.length_scale
    d = float(np.linalg.norm(c))
    if d < 1e3 * h or not fixed:
        return ""
    names = ", ".join(f"{getattr(ld, 'name', 'load')!r} ({type(ld).__name__})" for ld in fixed[:3])
    eps = np.finfo(float).eps * d
    return (f"the part lies {d:.3g} from the origin ({d / h:.2g} element sizes) and {names} "
            f"{'is' if len(fixed) == 1 else 'are'} not translation invariant, so the iterate is held in the "
            f"problem's coordinates, whose positions carry a round-off eps |x0| = {eps:.2g} ({eps / h:.2g} of an "
            "element) that can stall Newton (docs/STEPS.md, 'Translation invariance'); place the part and its "
            "obstacles (or fields, springs) near the origin, or give the obstacle as a built-in kind")


def restart_frames(origin, g, held, to_local):
    """The iterate a restart from the problem's frames ``g`` continues from: the frames the solver
    held at that state, ``held`` = (c, g_c) relative to its origin c (a restart state keeps them:
    ``NewtonState.held``, ``ArcState.held``), when c is ``origin`` and g_c + c is g to the bit;
    else ``to_local(g)``.  Frames taken back from g carry the round-off of its positions,
    eps |x0|: the snap roof at z = 2540 resumed from its absolute frames ended 1.4e-14 off the
    unbroken run; from the held ones it ends on its bits.

    Example
    -------
    >>> import numpy as np
    >>> c = np.array([0.0, 0.0, 2540.0])
    >>> g_c = np.eye(4)[None].copy(); g_c[0, 2, 3] = 0.1            # as the solver held it
    >>> g = g_c.copy(); g[0, 2, 3] += c[2]                            # the problem's frames: 2540.1
    >>> def to_local(g):
    ...     x = np.array(g); x[..., :3, 3] -= c; return x
    >>> float(to_local(g)[0, 2, 3]), float(restart_frames(c, g, (c, g_c), to_local)[0, 2, 3])
    (0.09999999999990905, 0.1)
    """
    if held is not None and origin is not None:
        c, g_c = (np.asarray(x, dtype=float) for x in held)
        if c.shape == (3,) and np.array_equal(c, origin) and g_c.shape == np.shape(g):
            whole = np.array(g_c)
            whole[..., :3, 3] += c
            if np.array_equal(whole, g):
                return np.array(g_c)
    return to_local(g)


def held_by(system, g):
    """(c, a copy of g): the frames ``g`` a solver ``system`` holds relative to its origin c
    (``NewtonEquations.origin``, ``ShellSystem.origin``), for a restart state; None when it has
    none (a part near the origin, a distributed run, an algebraic system)."""
    c = getattr(system, "origin", None)
    return None if c is None else (c, np.array(g))


def held_record(held):
    """(scalars, arrays) of a restart state's ``held`` = (c, g_c) or None, for a checkpoint: the
    origin as JSON floats (exact through repr) and the frames among the named arrays;
    :func:`held_of` reads them back.

    Example
    -------
    >>> import numpy as np
    >>> sc, arrays = held_record((np.array([0.0, 0.0, 2540.0]), np.eye(4)[None]))
    >>> sc, sorted(arrays), held_of(sc, arrays)[0].tolist(), held_record(None)
    ({'origin': [0.0, 0.0, 2540.0]}, ['held_frames'], [0.0, 0.0, 2540.0], ({'origin': None}, {}))
    """
    if held is None:
        return {"origin": None}, {}
    c, g_c = held
    return {"origin": [float(x) for x in c]}, {HELD: np.asarray(g_c, float)}


def held_of(scalars, arrays):
    """The ``held`` = (c, g_c) of a restart state's checkpoint record (:func:`held_record`), or
    None (none kept: a part near the origin, or a checkpoint written before they were)."""
    c = scalars.get("origin")
    if c is None or arrays is None or HELD not in arrays:
        return None
    return np.array(c, float), np.array(arrays[HELD], float)
