"""The Problem: mesh + material + element + supports + loads + probes, and the discrete equations
r(g, lam) = r_int(g) - f_ext(g, lam) and their tangent, evaluated in one place for every solver.

    p = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(E=1.2e6, nu=0.0, h=0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0, 0, 4.0))
    result = p.solve(steps=10)

State: the nodal frames g (n, 4, 4); update g_i <- g_i exp(eta_i) with eta the body-frame twist
(v, w) of node i (seed Algorithm 1, without its incremental strain update: strains are
recomputed from the current frames).  The residual and the tangent live on the free degrees of
freedom (those no support holds).  Solving is delegated to the solver registered under the
control's name (:data:`SOLVERS`, filled by :mod:`core_se3.solvers`), so that this layer does not
depend on the solvers.
"""
from __future__ import annotations

import warnings

import numpy as np

from .. import lie
from ..assembly import Assembler
from .. import backend as _backend
from ..errors import LoadError, LoadWarning, MaterialError, MeshError, OptionError, SupportError, did_you_mean
from ..fem import ELEMENTS, make_element
from ..fem.material import E_RANGE_PA
from ..mesh import Mesh
from .base import Evaluation, Load, check_given, force_scale_with_loads, linear_scale, load_kind, scale_knots
from .compiled import CompiledEvaluation
from .contact import add_obstacle
from .fields import B_MAX, FIELD_DEFECT_TOL, MU0, field_defect, field_vanishes, tesla_units
from .loads import element_area, line_shares, material_per_element
from .magnetics import (MagneticLoad, Magnetisation, br_numbers, dipole_sources, magnets_force, magnets_output,
                        table_kind)
from .probes import Probe, along_line
from .solving import SOLVERS, check_linear_solver, dispatch, solve_linear
from .supports import (LabSpring, LabTiltSpring, Prescribed, RotationComponentSpring, check_conflict,
                       check_rigid_motions, apply_prescribed, fixed_dofs, prescribed_rotation, rigid_motion,
                       select_nodes)

__all__ = ["Problem", "Evaluation", "SOLVERS"]


def _frames(g, n_nodes):
    """The state ``g`` as a float array of one 4x4 frame per node, else a MeshError naming the
    shapes: the compiled kernels index the frames by node id without bounds checks, so a state of
    fewer frames than nodes read memory past its end (a misleading 'edge turns by inf rad', or a
    plausible residual), and NumPy failed with a bare IndexError."""
    g = np.asarray(g, dtype=float)
    if g.shape != (n_nodes, 4, 4):
        raise MeshError(f"a state of frames of shape {g.shape} for a mesh of {n_nodes} nodes: give one 4x4 "
                        f"frame per node, shape ({n_nodes}, 4, 4) (the mesh of this problem, not another's)")
    return g


def _per_row(a, rows, cols, what, per):
    """``a`` as a float array (rows, cols), given so or flat (rows * cols,), else a MeshError
    naming the shapes: a (cols, rows) array has the size and was read as (rows, cols) in the
    wrong order (the mixed tangent of transposed stresses 35 % off, silently)."""
    a = np.asarray(a, dtype=float)
    if a.shape == (rows * cols,):
        return a.reshape(rows, cols)
    if a.shape != (rows, cols):
        raise MeshError(f"{what} of shape {a.shape}: give one row of {cols} per {per}, shape ({rows}, {cols}) "
                        f"(or flat, ({rows * cols},))")
    return a


def _warn_thickness_loads(problem, old, new):
    """LoadWarning (at the caller of ``Problem.material = ...`` / ``set_material``) when the new
    law changes the thickness while loads built on the old one are on the problem: a magnet (its
    dipoles h B^r / mu0), gravity (rho h g) or a contact (its face at h/2) keep the old h -- a
    cantilever under gravity given h 0.1 -> 0.2 deflected 1533 instead of the 3066 of a problem
    built with h 0.2 (linear), as documented but without a word."""
    m = problem.mesh.n_elements
    try:
        changed = material_per_element(old, "h", m) != material_per_element(new, "h", m)
    except (AttributeError, TypeError, ValueError):
        return                                   # (a law without h: the element will say so)
    if not changed.any():
        return
    nodes = np.zeros(problem.mesh.n_nodes, bool)
    nodes[problem.mesh.quads[changed].ravel()] = True
    kept = set()
    for ld in problem.loads:         # the loads on the changed elements (as design.material's check)
        el = getattr(getattr(ld, "mag", None), "elements", None)
        if el is not None and np.any(changed[el]):
            kept.add("magnet")
        elif getattr(ld, "name", "") == "gravity" and np.any(changed[getattr(ld, "elements", slice(None))]):
            kept.add("gravity")
        elif type(ld).__name__ == "ContactLoad" and np.any(nodes[ld.nodes]):
            kept.add("contact")
    if kept:
        kept = sorted(kept)
        warnings.warn(LoadWarning(f"the new material changes the thickness h on {int(changed.sum())} element(s), but the "
                                  f"problem's {', '.join(kept)} load(s) keep the h they were built with (their h B^r / "
                                  "mu0, rho h g, h/2 face): build the Problem anew with the new material, or set the "
                                  "material before adding those loads"), stacklevel=3)


def _warn_field_defect(field, x, where):
    """LoadWarning (at add_magnetic's caller) for an applied field with a curl or a divergence at
    the magnetised points ``x`` (``fields.field_defect``): a user field the magnets' loads are
    not right for (a user field with a curl as large as its gradient was taken as given, and the
    magnets' force (B^r . grad) B^a missed its m x curl B part, converged and silent)."""
    try:
        curl, div = field_defect(field, x)
    except LoadError:
        return                                   # (the field's own error comes with the load)
    if max(curl, div) > FIELD_DEFECT_TOL:
        said = LoadWarning(f"add_magnetic: the applied field has a curl or a divergence on {where} (relative "
                           f"|curl B| {curl:.2e}, |div B| {div:.2e}, to |grad B|, above {FIELD_DEFECT_TOL:g}): the "
                           "magnets' couple and force hold for a field without currents or sources in the body only, "
                           "so the answer misses their part; give a curl- and divergence-free field (fields.check_field)")
        said.cause = "field_defect"
        warnings.warn(said, stacklevel=3)


def _warn_magnet_units(problem, loads, field, x, mu0, where):
    """LoadWarning (at add_magnetic's caller) for a magnet whose numbers disagree with the units of
    its ``mu0``, when that is of a unit system in tesla (``fields.tesla_units``: MU0 times a power
    of ten): a |B^r| or an applied |B^a| at the magnetised points ``x`` at load factor 1 above
    ``fields.B_MAX`` = 2 T (1000 times that for a field with a point dipole, strong near its
    source) -- mT, or a magnetisation M [A/m] given as B^r --, and a Young's modulus of the
    magnetised elements outside the range of real solids in the stress unit that mu0 fixes (Pa
    for MU0, MPa for MU0 * 1e6: ``fem.material.E_RANGE_PA``) -- an N-mm-MPa model given SI's
    default mu0 has loads 1e6 times too strong.  A scenario says these at the file's keys (its
    plausibility check).  Before, the Python API ran Zhao's strip given Br = 143 (mT meant), or in
    mm and MPa without mu0, to a converged tip without a word."""
    if not tesla_units(mu0):
        return
    said = _tesla_said(loads, field, x)
    els = np.concatenate([ld.mag.elements for ld in loads])
    try:
        E = material_per_element(problem.material, "E", problem.mesh.n_elements)[els] * (mu0 / MU0)    # [Pa]
    except (AttributeError, TypeError, ValueError):
        E = np.zeros(0)                          # (a law without E)
    E = E[np.isfinite(E)]
    if len(E) and not (E_RANGE_PA[0] <= E.min() and E.max() <= E_RANGE_PA[1]):
        e = E.min() if E.min() < E_RANGE_PA[0] else E.max()
        unit = {0: "Pa", 3: "kPa", 6: "MPa", 9: "GPa"}.get(int(round(np.log10(mu0 / MU0))), f"{mu0 / MU0:g} Pa")
        said.append(f"mu0 = {mu0:.6g} makes stresses {unit}, so E = {e / (mu0 / MU0):g} is {e:.3g} Pa, outside "
                    f"the range of real solids ({E_RANGE_PA[0]:g} Pa .. 700 GPa): give mu0 in the units of E "
                    "(fields.MU0 for Pa, MU0 * 1e6 for N-mm-MPa)")
    said += _dipole_said(field, mu0)
    if said:
        w = LoadWarning(f"add_magnetic on {where}: {'; '.join(said)}")
        w.cause = "units"
        warnings.warn(w, stacklevel=3)


def _dipole_said(field, mu0):
    """The message of ``_warn_magnet_units`` for a point dipole of ``field`` whose mu0 is not the
    one of the magnets' units: SI (magnets MU0) needs the dipole's MU0, N-mm-MPa (magnets MU0 *
    1e6) MU0 * 1e3 (m in A mm^2, r in mm); other units are not checked.  The default (SI's)
    dipole in an N-mm-MPa model made a field 1000 times too weak, the magnets' MU0 * 1e6 1000
    times too strong."""
    units = {0: ("SI", MU0, "m"), 6: ("N-mm-MPa", MU0 * 1e3, "mm")}.get(int(round(np.log10(mu0 / MU0))))
    for d in dipole_sources(field) if units else ():
        name, want, length = units
        k = 4 * np.pi * d.k
        if abs(k / want - 1) > 1e-6:
            return [f"the point dipole at x0 = {d.x0.tolist()} has mu0 = {k:.6g}, but with the magnets' mu0 = "
                    f"{mu0:.6g} ({name}) a dipole's is {want:.6g} (B = mu0 m / (4 pi r^3) in T for m in A {length}^2 "
                    f"and r in {length}): its field is {k / want:.6g} times the meant one; give DipoleField(..., mu0="
                    f"{'MU0' if name == 'SI' else 'MU0 * 1e3'})"]
    return []


def _tesla_said(loads, field, x):
    """The messages of ``_warn_magnet_units`` for a |B^r| or |B^a| (at load factor 1) above 2 T."""
    br = max(ld.mag.br_max for ld in loads)
    try:
        ba = float(np.linalg.norm(field.value(x, 1.0), axis=1).max())
    except LoadError:
        ba = 0.0                                 # (a dipole on a node: the load says so when evaluated)
    said = []
    if br > B_MAX:
        said.append(f"|Br| = {br:g} T exceeds {B_MAX:g} T (the strongest permanent magnets, NdFeB, reach about "
                    "1.4 T): Br is the residual flux density in tesla (M = Br/mu0: M = 1.14e5 A/m is Br = 0.143 T); "
                    "did you give mT?")
    if ba > B_MAX * (1e3 if dipole_sources(field) else 1.0):
        said.append(f"the applied field reaches |B| = {ba:g} T at load factor 1, above {B_MAX:g} T (lab "
                    "electromagnets): B is in tesla; did you give mT?")
    return said


class Problem:
    """A shell problem.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The reference mesh (named node sets and regions are usable by name everywhere below).
    material : core_se3.Material or core_se3.RegionMaterial
        The resultant law (one law, or one per element).
    element : str
        A key of ``core_se3.fem.ELEMENTS`` ('default': exact edge twists; 'seed': the seed's).
    linear_solver : str
        'auto', 'banded', 'superlu' or 'mumps' (see ``core_se3.solvers.linalg``); an unknown name,
        or 'mumps' without petsc4py, is an :class:`~core_se3.errors.OptionError` here, naming the
        choices on this machine (``model.solving.check_linear_solver``).
    backend : str, optional
        'numba' (compiled kernels), 'numpy' (the reference) or 'auto' (NumPy until numba pays
        for its start, then numba: ``core_se3.backend``); default ``core_se3.backend``'s.

    Attributes
    ----------
    element : core_se3.fem.Element
        The element on the whole mesh, built at first use (a distributed run builds its own).
    loads, supports : list
        The Load objects and the Prescribed supports added so far; ``probes``: name -> Probe.
    solve_defaults : dict
        Options :meth:`solve` uses unless given (a scenario's [solver] settings).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(E=1.2e6, nu=0.0, h=0.1))
    >>> p.clamp("x0")
    >>> p.add_edge_force("x1", (0.0, 0.0, 4.0))
    >>> p.add_probe("tip", "x1")
    >>> res = p.solve(steps=10)
    >>> round(float(res.final.probes["tip"]["u"][2]), 3)                 # Sze et al. 2004: 6.7
    6.696
    """

    def __init__(self, mesh, material, element="default", linear_solver="auto", backend=None):
        self.backend = backend
        self.loads = []
        self.supports = []
        self.probes = {}
        self.mesh = mesh                              # sets length_scale
        self.material = material
        self.element_name = element                   # an unknown name fails here; built at first use
        self.linear_solver = linear_solver            # an unknown or unavailable name fails here
        self.solve_defaults = {}
        self.scale_tables = []       # the loads' piecewise-linear programmes (note_scale)
        self.untabled_scales = []    # their other callable programmes, searched for turns (note_scale)

    def note_scale(self, scale):
        """Keep a load-factor programme ``scale``.  Load stepping lands a try on the points of a
        :class:`~core_se3.model.ScaleTable` (:attr:`scale_knots`, ``solvers.newton``), and path
        following refuses its kinks (``solvers.system``); any other callable is kept in
        ``untabled_scales``, and load stepping ends a try at its first peak or trough inside the
        try (``solvers.splitting.first_turn``, found on 64 samples of the try).

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> from core_se3.model import ScaleTable
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
        >>> p.note_scale(ScaleTable([[0.0, 0.0], [0.5, 1.0], [1.0, 0.0]])); p.scale_knots
        (0.0, 0.5, 1.0)
        """
        if scale_knots(scale):
            if all(t is not scale for t in self.scale_tables):
                self.scale_tables.append(scale)
        elif callable(scale) and scale is not linear_scale:
            # any other callable: load stepping ends a try on its first peak or trough inside the
            # try, found on samples (``solvers.splitting.first_turn``)
            untabled = self.__dict__.setdefault("untabled_scales", [])
            if all(t is not scale for t in untabled):
                untabled.append(scale)

    @property
    def scale_knots(self):
        """The load factors of the points of every noted scale table, sorted."""
        return tuple(sorted({t for table in getattr(self, "scale_tables", ()) for t in scale_knots(table)}))

    @property
    def linear_solver(self):
        """The linear solver's name; setting it checks it (``model.solving.check_linear_solver``:
        an OptionError naming the choices on this machine, not a failure when a solve begins)."""
        return self._linear_solver

    @linear_solver.setter
    def linear_solver(self, name):
        self._linear_solver = check_linear_solver(name)

    @property
    def mesh(self):
        """The reference mesh.  Setting another mesh drops what was built on the old one (the
        element, the compiled evaluation, the assembler) and sets :attr:`length_scale` to the new
        mesh's; setting the same mesh does nothing.  Supports, loads and probes hold node ids and
        data of the mesh they were added on: once any was added, setting another mesh raises a
        :class:`~core_se3.errors.MeshError` (a stale support would hold the old mesh's node ids on
        the new one) -- build a new Problem on the new mesh, or set the mesh before adding them.

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
        >>> p.mesh = mesh.rectangle(4.0, 1.0, 4, 1); p.element.mesh.n_elements, p.length_scale == p.mesh.length_scale
        (4, True)
        >>> p.clamp("x0"); p.mesh = mesh.rectangle(1.0, 1.0, 2, 1)    # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        core_se3.errors.MeshError: cannot set another mesh on a Problem with supports, loads or probes added (1 support(s)): ...
        """
        return self._mesh

    @mesh.setter
    def mesh(self, new):
        if getattr(self, "_mesh", None) is new:
            return
        if not isinstance(new, Mesh):           # (a bare AttributeError before)
            raise MeshError(f"a Problem's mesh must be a core_se3.mesh.Mesh (a generator's, mesh.read_meshio's or "
                            f"Mesh(g0, quads)), got {type(new).__name__}")
        added = [f"{len(x)} {name}" for name, x in (("support(s)", self.supports), ("load(s)", self.loads),
                                                    ("probe(s)", self.probes)) if x]
        if added:
            raise MeshError(f"cannot set another mesh on a Problem with supports, loads or probes added "
                            f"({', '.join(added)}): they refer to the old mesh's node ids and data; build a new "
                            f"Problem on the new mesh (or set the mesh before adding them)")
        self._mesh = new
        self.length_scale = new.length_scale
        self._element = None
        self._compiled = None
        self._assembler = None

    @property
    def backend(self):
        """The backend evaluating now, 'numba' or 'numpy' (``backend_setting`` 'auto' goes from
        the one to the other: ``core_se3.backend.active``); set it to any setting."""
        return _backend.active(self.backend_setting)

    @backend.setter
    def backend(self, name):
        self.backend_setting = _backend.resolve(name)

    @property
    def material(self):
        """The resultant law; setting it (as :meth:`set_material`) drops the element built for the
        old one and the compiled evaluation, so the next evaluation uses the new law (a law set
        after a solve was silently ignored: the element kept the old one)."""
        return self._material

    @material.setter
    def material(self, law):
        if not callable(getattr(law, "resultant_matrix", None)):      # (a bare AttributeError at first use)
            raise MaterialError(f"a Problem's material must be a resultant law (core_se3.Material, RegionMaterial, "
                                f"Material.classical_shell(...)), got {type(law).__name__}")
        old = getattr(self, "_material", None)
        self._material = law
        self._element = None
        self._compiled = None
        if old is not None and self.loads:
            _warn_thickness_loads(self, old, law)

    @property
    def element_name(self):
        """The element's key in ``core_se3.fem.ELEMENTS``; setting it (an unknown name fails)
        drops the element built for the old one, as setting :attr:`material` does."""
        return self._element_name

    @element_name.setter
    def element_name(self, name):
        ELEMENTS.lookup(name)
        self._element_name = name
        self._element = None
        self._compiled = None

    @property
    def element(self):
        """The element on the whole mesh (``fem.make_element``), built at its first use."""
        if self._element is None:
            self._element = make_element(self.element_name, self.mesh, self.material)
        return self._element

    @element.setter
    def element(self, value):
        self._element = value

    # ---------------------------------------------------------------- selections -------
    def nodes(self, where):
        """Node ids of a selection: a node-set or region name, a predicate of the reference
        positions, or ids (each once: ``supports.select_nodes``)."""
        return select_nodes(self.mesh, where)

    def node_at(self, x, tol=None):
        """The id of the node at the point x (``Mesh.node_at``: the nearest node, within tol)."""
        return self.mesh.node_at(x, tol)

    def elements(self, region):
        """Element ids of a region name or of ids (None: all elements, returned as None)."""
        if region is None:
            return None
        try:
            return self.mesh.elements(region)
        except MeshError as exc:
            raise LoadError(str(exc)) from None

    # ---------------------------------------------------------------- supports ---------
    def _support(self, s, name=None):
        """Add the Prescribed ``s`` (named ``name``: the key of its reaction in
        ``StepResult.support_reactions``; None: ``supports[i]``, its index)."""
        check_conflict(self.supports, s)          # a node moved by two supports: refused
        s.name = None if name is None else str(name)
        self.supports.append(s)
        self._assembler = None

    def clamp(self, where, name=None):
        """Fix position and rotation of the selected nodes at their reference values (``name``:
        of its reaction in ``StepResult.support_reactions``, default ``supports[i]``; so for
        every support)."""
        self._support(Prescribed(self.nodes(where), np.ones(6, bool)), name)

    def fix(self, where, dofs, name=None):
        """Fix selected body-frame dofs (0-2 translations along d1..d3, 3-5 rotations)."""
        self._support(Prescribed(self.nodes(where), fixed_dofs(dofs)), name)

    def rotate_edge(self, where, axis, angle, point=(0.0, 0.0, 0.0), free=(), scale=None, name=None):
        """Rigidly rotate the selected nodes about ``axis`` through ``point`` by angle*scale(lam).

        ``free``: lab translation directions (0 = x, 1 = y, 2 = z) left free; each must stay
        aligned with a body axis of every selected node: a body axis parallel to the rotation
        axis (e.g. a strip end twisted about the strip axis, free along it).
        """
        self._support(rigid_motion(self.mesh, self.nodes(where), (0.0, 0.0, 0.0), axis, angle, point, free, scale),
                      name)
        self.note_scale(scale)

    def move_edge(self, where, translate=(0.0, 0.0, 0.0), axis=None, angle=0.0, point=None, free=(), scale=None,
                  name=None):
        """Move the selected nodes rigidly: rotated by angle*s about ``axis`` through ``point``
        (default their centroid), then translated by s*translate, s = scale(lam) (default lam);
        ``free`` as for :meth:`rotate_edge` (``supports.rigid_motion``)."""
        self._support(rigid_motion(self.mesh, self.nodes(where), translate, axis, angle, point, free, scale), name)
        self.note_scale(scale)

    def prescribe(self, where, target, fixed=(True,) * 6, name=None):
        """Selected nodes follow ``target(lam) -> (k, 4, 4)`` frames on the fixed dofs.  Linear
        analysis holds the chord of the target at lam_end (an AccuracyWarning if the target is not
        linear in lam): give rigid motions with :meth:`rotate_edge` / :meth:`move_edge`."""
        self._support(Prescribed(self.nodes(where), np.asarray(fixed, bool), target), name)

    def add_lab_support(self, where, dirs, k, name=None):
        """Hold the lab displacement components ``dirs`` of the selected nodes by penalty springs
        of stiffness k (supports.LabSpring): ``dirs`` (q, 3) is a set of q <= 3 independent
        directions held at *every* selected node ((3,): one; (1, q, 3): the same, explicitly), (n,
        q, 3) a set per node for the n selected nodes -- one direction per node is (n, 1, 3), not
        (n, 3) (that is a set held at every node, refused beyond 3 rows, and refused as ambiguous
        when q == n > 1 with different rows: give (n, 1, 3) or (1, q, 3)).  Rows are normalised.
        ``name``: of its reaction (``StepResult.support_reactions``; default ``loads[j]``)."""
        return self._spring(LabSpring(self.mesh, self.nodes(where), dirs, k), name)

    def _spring(self, spring, name):
        spring.support_name = None if name is None else str(name)
        return self.add(spring)

    def add_lab_tilt_support(self, where, t, k_rot, name=None):
        """Keep the normals of the selected nodes normal to the lab directions ``t`` by a
        rotational penalty (supports.LabTiltSpring): ``t`` (3,) or (1, 3) is one direction for
        every selected node, (n, 3) one row per node for the n selected nodes (unlike
        :meth:`add_lab_support`'s (q, 3), a set held at every node); ``name`` as there."""
        return self._spring(LabTiltSpring(self.mesh, self.nodes(where), t, k_rot), name)

    def add_rotation_component_support(self, where, a, k_rot, name=None):
        """Hold the lab component ``a`` of the total rotation vector of the selected nodes at
        zero by a rotational penalty (supports.RotationComponentSpring); ``name`` as for
        :meth:`add_lab_support`."""
        return self._spring(RotationComponentSpring(self.mesh, self.nodes(where), a, k_rot), name)

    # ---------------------------------------------------------------- loads ------------
    def add(self, load):
        """Add any :class:`~core_se3.model.Load` instance; returns it.  LoadError for one that is
        in the problem already (it would act twice, silently: ``p.add(p.loads[0])`` doubled the
        load)."""
        if not isinstance(load, Load):
            raise LoadError(f"expected a core_se3.model.Load, got {type(load).__name__}")
        same = next((j for j, ld in enumerate(self.loads) if ld is load), None)
        if same is not None:
            raise LoadError(f"this load ({getattr(load, 'name', 'load')!r}) is loads[{same}] of the problem already: "
                            "adding it again would apply it twice; for a load meant twice, double its value "
                            "(or build a second one)")
        self.loads.append(load)
        self.note_scale(getattr(load, "scale", None))    # its table's points / its turns are stepped onto
        return load

    def add_load(self, kind, where=None, scale=None, check=True, **values):
        """Add a load of a registered kind (``core_se3.model.LOADS``) on ``where`` (a line or
        node selection for 'line'/'nodes' kinds, a region or element ids for 'elements' kinds,
        default all; for 'line' kinds also a list of line names, e.g. ["x0", "x1"]: each line
        along its own element edges, with its share of the total by length); returns the list
        of loads added.  ``check=False`` skips the kind's
        cross-key check (a scenario file has run it on the keys its user wrote).

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
        >>> [type(ld).__name__ for ld in p.add_load("pressure", p=2.0)]
        ['SurfaceLoad']
        """
        k = load_kind(kind)
        if scale is not None and not callable(scale):
            raise LoadError(f"load kind {kind!r}: scale must be a function of the load factor (lam -> s; default "
                            f"s = lam, constant: lambda lam: 1.0), got {scale!r}")
        names = {p.name for p in k.params}
        for key in values:
            if key not in names:
                raise LoadError(f"load kind {kind!r} has no parameter {key!r}{did_you_mean(key, names)}; "
                                f"its parameters: {', '.join(sorted(names))}")
        for p in k.params:
            if p.required and p.name not in values:
                raise LoadError(f"load kind {kind!r} needs {p.name!r}")
        check_given(k, values)
        full = {p.name: values.get(p.name, p.default) for p in k.params}
        if check and k.check is not None:
            bad = k.check(full, set(values))
            if bad is not None:
                raise LoadError(bad[1])
        self.note_scale(scale)
        if k.target == "line" and _names(where):
            return self._add_on_lines(k, where, scale, full)
        try:
            selection = self.nodes(where) if k.target in ("line", "nodes") else self.elements(where)
        except (LoadError, MeshError, SupportError) as exc:     # the selection's own words, for a load
            what = "a line or node set name, a predicate or node ids" if k.target != "elements" else \
                "a region name or element ids"
            raise LoadError(f"load kind {kind!r}: the selection {where!r} ({what}): {exc}") from None
        built = k.build(self, selection, scale, **full)
        built = built if isinstance(built, (list, tuple)) else [built]
        return [self.add(ld) for ld in built]

    def _add_on_lines(self, kind, names, scale, values):
        """A 'line' load on a union of named lines: one load per line, its scale times the line's
        share of the length (``loads.line_shares``), so that each line keeps its own element edges
        (one node set of both ends of a one-element strip closed a loop through its sides)."""
        base = scale or linear_scale
        added = []
        for name, share in zip(names, line_shares(self.mesh, names)):
            built = kind.build(self, self.nodes(name), lambda lam, f=float(share): f * base(lam), **values)
            added += [self.add(ld) for ld in (built if isinstance(built, (list, tuple)) else [built])]
        return added

    def add_edge_force(self, where, total_force, follower=False, scale=None):
        """Total force distributed consistently along an edge (lab vector if dead; components
        in each node's frame d1, d2, d3 if follower)."""
        self.add_load("edge_force", where, scale, force=total_force, follower=follower)

    def add_edge_moment(self, where, total_moment, follower=False, scale=None):
        """Total moment distributed consistently along an edge (as add_edge_force)."""
        self.add_load("edge_moment", where, scale, moment=total_moment, follower=follower)

    def add_nodal_load(self, where, force=(0, 0, 0), moment=(0, 0, 0), follower=False, scale=None):
        """The same force and moment on each selected node."""
        self.add_load("nodal", where, scale, force=force, moment=moment, follower=follower)

    def add_pressure(self, p, direction=None, follower=False, scale=None, elements=None):
        """Pressure p [force/length^2]: follower -> along the current normal per current area;
        dead -> along the lab ``direction`` (default +z; normalised) per reference area."""
        kw = {} if direction is None else dict(direction=direction)
        self.add_load("pressure", elements, scale, p=p, follower=follower, **kw)

    def add_body_force(self, q, scale=None, elements=None):
        """Dead force per unit reference area (e.g. gravity rho h g), lab vector."""
        self.add_load("body_force", elements, scale, q=q)

    def add_gravity(self, rho=None, g=(0.0, 0.0, -9.81), elements=None, scale=None):
        """Self-weight: dead body force rho h g per unit reference area (rho [mass/length^3],
        default the material's; g [length/time^2] lab vector; default SI, -z).  The same load as
        ``add_load("gravity", ...)``: a negative or non-finite rho is a LoadError, rho = 0 adds
        nothing with a LoadWarning naming rho (a sweep may start weightless).  Returns the loads."""
        with warnings.catch_warnings(record=True) as seen:       # said at the caller's line, not here
            warnings.simplefilter("always")
            loads = self.add_load("gravity", elements, scale, g=g, rho=rho)
        for w in seen:
            warnings.warn(w.message, stacklevel=2)
        return loads

    def add_magnetic(self, Br, field, elements=None, mu0=None, Br_per=None):
        """Hard-magnetic material of residual flux density ``Br`` [T] (lab, reference
        configuration; 3-vector, per selected element, per node, or function of position) on
        ``elements`` (region or ids, default all) in the applied field ``field``
        (core_se3.model.fields): body couple h/mu0 B^r_t x B^a and body force
        h/mu0 (B^r_t . grad) B^a per unit reference area, with B^r_t = R_t R_0^T B^r_0
        (seed E48-E50).  ``mu0`` must match the units (fields.MU0 for Pa; MU0 * 1e6 for
        N-mm-MPa).  Where the thickness differs between elements, one load per thickness.
        ``Br_per`` ('element' or 'node') says which table an array ``Br`` is: needed only when
        the selection has as many elements as the mesh has nodes (a closed mesh: a LoadError
        without it).  Returns the load (its ``mag.nodes`` are the magnetised nodes), or the list
        of loads.  A Br that is zero on every selected element adds nothing, with a LoadWarning
        (a sweep may start at zero), and so does a field that is zero (value and gradient at
        scale 1, ``fields.field_vanishes``) at every magnetised node; Br, mu0 or elements of the
        wrong type are a LoadError.  With a mu0 of tesla units (``fields.tesla_units``) a LoadWarning
        says numbers that disagree with them: |Br| or |Ba| (at load factor 1) above 2 T (mT meant?),
        an E of the magnetised elements outside 10 Pa .. 700 GPa in the stress unit mu0 fixes (MU0:
        Pa, MU0 * 1e6: MPa), a point dipole's mu0 not of the magnets' units (docs/MAGNETICS.md)."""
        mu0 = MU0 if mu0 is None else mu0
        try:
            sel = self.elements(elements)
        except LoadError as exc:
            raise LoadError(f"add_magnetic: elements={elements!r} (a region name or element ids): {exc}") from None
        with warnings.catch_warnings(record=True) as seen:     # said at the caller's line, not here
            warnings.simplefilter("always")
            added = self._add_magnetic(Br, field, sel, mu0, Br_per)
        for part in getattr(field, "fields", (field,)):      # a Superposition's parts
            self.note_scale(getattr(part, "scale", None))
        for w in seen:
            warnings.warn(w.message, stacklevel=2)
        built = added if isinstance(added, list) else [added]
        where = "the whole shell" if elements is None else f"elements={elements!r}"
        nodes = np.unique(np.concatenate([np.asarray(ld.mag.nodes, np.int64) for ld in built]))
        if not len(nodes):
            warnings.warn(LoadWarning(f"add_magnetic: Br is zero on {where}: the magnet adds no load (a sweep may "
                                      "start at zero); give its residual flux density [T], or drop the magnet"),
                          stacklevel=2)
        elif field_vanishes(field, self.mesh.X[nodes]):
            said = LoadWarning(f"add_magnetic: the applied field is zero on {where} (its value and gradient at "
                               "every magnetised node): the magnet adds no load (a sweep may start at zero); give "
                               "the field's B [T], or drop the magnet")
            said.cause = "field"            # (the scenario names the field's key)
            warnings.warn(said, stacklevel=2)
        else:
            _warn_field_defect(field, self.mesh.X[nodes], where)
        if len(nodes):
            _warn_magnet_units(self, built, field, self.mesh.X[nodes], mu0, where)
        return added

    def _add_magnetic(self, Br, field, sel, mu0, Br_per):
        """``add_magnetic`` on the element ids ``sel`` (None: all): one load, or one per thickness."""
        per = getattr(self.material, "per_element", None)
        h_all = per("h") if per is not None else None
        ids = np.arange(self.mesh.n_elements) if sel is None else np.asarray(sel)
        j0 = element_area(self, ids)                 # the element's own area on curved elements
        if h_all is None or len(np.unique(h_all)) == 1:
            h = self.material.h if h_all is None else float(h_all[0])
            return self.add(MagneticLoad(Magnetisation(self.mesh, Br, h, sel, mu0, Br_per, j0), field))
        h = h_all[ids]
        # one load per thickness: a table per selected element is split with the elements; a
        # 3-vector, a table per node and a function of position hold for every part as given
        per = None                  # None: a 3-vector or a function of position
        if not callable(Br):
            Br = br_numbers(Br)
            per = None if Br.shape == (3,) else table_kind(Br.shape, len(ids), self.mesh.n_nodes, Br_per)
        per_element = per == "element"
        return [self.add(MagneticLoad(Magnetisation(self.mesh, Br[h == t] if per_element else Br, float(t),
                                                    ids[h == t], mu0, per, None if j0 is None else j0[h == t]),
                                      field))
                for t in np.unique(h)]

    def set_material(self, material):
        """Replace the material law (a design changes E or h per region): the element is rebuilt
        for it and the compiled evaluation is dropped (loads keep their own data: a magnetisation
        or gravity built from the old thickness is not updated).

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
        >>> p.set_material(Material(2e3, 0.0, 0.01)); p.material.E, p.element.material.E
        (2000.0, 2000.0)
        """
        with warnings.catch_warnings(record=True) as seen:       # said at the caller's line, not here
            warnings.simplefilter("always")
            self.material = material                 # drops the element and the compiled evaluation
        for w in seen:
            warnings.warn(w.message, stacklevel=2)
        self.element = make_element(self.element_name, self.mesh, material)

    def add_obstacle(self, obstacle, region=None, nodes=None, **options):
        """Contact with a rigid obstacle: a registered kind ('half_space', 'sphere', 'cylinder',
        'box') with its parameters and ``motion``, or an Obstacle; options ``name``, ``side``,
        ``friction`` and ``law`` (a ``ContactLaw`` or a dict of it: mode, beta, eps, tol,
        cap_depth, ...) (``model.contact.add_obstacle``).  Returns the ContactLoad.

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e4, 0.0, 0.02))
        >>> p.add_obstacle("sphere", centre=(0.5, 0.0, 0.5), radius=0.4).name
        'sphere'
        """
        motion = options.get("motion")
        if isinstance(motion, dict):
            self.note_scale(motion.get("scale"))
        return add_obstacle(self, obstacle, region, nodes, **options)

    def add_probe(self, name, where="x1"):
        """Record the midpoint of an edge (or a node) at every step (names are unique): the
        selected nodes ordered along the line they form (``probes.along_line``), halfway along
        the geodesic of their frames in the mesh's least-turn gauge (``Probe``: the user's choice
        of d1 at each node does not move it)."""
        if name in self.probes:
            raise OptionError(f"a probe named {name!r} exists already; give this one another name")
        line = along_line(self.mesh, self.nodes(where), name)
        self.probes[name] = Probe.edge_midpoint(name, line, self.mesh.gauge_angles if len(line) % 2 == 0 else None,
                                                self.mesh.g0)

    def output_fields(self, g, lam=1.0):
        """Extra point fields for output (name -> (n, k)) summed over the loads (magnetisation,
        magnetic couple and force per unit area, ...; empty without such loads); the magnets'
        together (``magnetics.magnets_output``: per unit area of all the magnetised elements)."""
        mags = [ld for ld in self.loads if isinstance(ld, MagneticLoad)]
        out = magnets_output(mags, g, lam) if mags else {}
        for load in self.loads:
            if isinstance(load, MagneticLoad):
                continue
            for k, v in load.output_fields(g, lam).items():
                out[k] = out[k] + v if k in out else v
        return out

    # ---------------------------------------------------------------- supports check ---
    def constraint_mask(self):
        """(n, 6) booleans: the dofs held by supports."""
        fixed = np.zeros((self.mesh.n_nodes, 6), bool)
        for s in self.supports:
            fixed[s.nodes] |= s.fixed
        return fixed

    def free_edge_elements(self):
        """(m,) booleans: the elements along a free edge -- a boundary edge (``Mesh.boundary_edges``)
        with a node whose translation nothing holds: no support holds a translation dof of it and
        no translational support spring (``add_lab_support``) acts on it.  Rotations held alone
        leave the edge free: the roof 2x2 at R/h 1e4 with its free edge's drilling rotations held
        is still 9.4 times its converged deflection.

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(3.0, 1.0, 3, 1), Material(1e3, 0.0, 0.01))
        >>> p.clamp("x0"); p.fix("x1", (2,)); p.fix("y0", (5,))
        >>> p.free_edge_elements().tolist()           # y0 and y1 are free along all three
        [True, True, True]
        >>> p.clamp("y0"); p.clamp("y1"); p.free_edge_elements().tolist()
        [False, False, False]
        """
        held = self.constraint_mask()[:, :3].any(1)
        for ld in self.loads:
            if getattr(ld, "holds_translations", False):
                held[ld.nodes] = True
        edges, owner = self.mesh.boundary_edges()
        free = np.zeros(self.mesh.n_elements, bool)
        free[owner[~held[self.mesh.edge_nodes[edges]].all(1)]] = True
        return free

    def check_element(self, index=None, size=None, warn=True, stacklevel=2, note=""):
        """The element's coarse-mesh check with the supports known: an ElementWarning
        (``fem.element_default.warn_if_coarse_thin_curved``) where an element along a free edge
        (:meth:`free_edge_elements`) has the coarse-curvature index phi^3 L / h above 2; ``solve``
        calls it.  Returns the free-edge layer's width l those elements imply (None: none).

        Parameters
        ----------
        index, size : (m,) ndarray, optional
            The element's ``coarse_curvature`` and sqrt(area) per element (default: this
            problem's element's; the distributed solver gathers them from its ranks).  An element
            without the index (the seed's) has nothing to check.
        warn : bool
            False: only the width (check-mesh's verdict).
        stacklevel : int
            The warning's, counted from the caller of this method.
        note : str
            A sentence appended to the warning (where a design met it).

        Example
        -------
        >>> import warnings
        >>> from core_se3.catalogue import shell_course as sc
        >>> p, _ = sc.scordelis_lo(4, h=2.5e-3)                        # R/h 1e4
        >>> with warnings.catch_warnings(record=True) as said:
        ...     warnings.simplefilter("always")
        ...     width = p.check_element()
        >>> round(width, 2), len(said)                                 # 1.144 R (h/R)^(1/4)
        (2.86, 1)
        """
        from ..fem.element_default import free_edge_layer_width, warn_if_coarse_thin_curved
        if index is None:
            index = getattr(self.element, "coarse_curvature", None)
            if index is None:
                return None
            size = np.sqrt(self.element.area)
        index = np.where(self.free_edge_elements(), index, 0.0)
        if warn:
            warn_if_coarse_thin_curved(index, size, stacklevel=stacklevel + 1, note=note)
        return free_edge_layer_width(index, size)

    def assembler(self):
        """The sparse assembler on the free dofs (built once per set of supports)."""
        if self._assembler is None:
            self._assembler = Assembler(self.mesh, ~self.constraint_mask().ravel())
        return self._assembler

    def check_supports(self, g=None):
        """Raise SingularSystemError if the supports (with the lab directions that loads such as
        penalty springs hold) leave a rigid-body motion free (``supports.check_rigid_motions``)."""
        check_rigid_motions(self, self.mesh.g0 if g is None else g)

    # ---------------------------------------------------------------- prescribed motion -
    @property
    def has_prescribed_motion(self):
        """True when a support follows a target motion of the load factor."""
        return any(s.target is not None for s in self.supports)

    def prescribed_rotation(self, lam0, lam1, samples=16):
        """Largest rotation [rad] a prescribed motion turns any node through between load
        factors lam0 and lam1 (``supports.prescribed_rotation``)."""
        return prescribed_rotation(self.supports, lam0, lam1, samples)

    def apply_prescribed(self, g, lam):
        """Set the frames of prescribed nodes to their targets at lam (in place); returns g
        (``supports.apply_prescribed``)."""
        return apply_prescribed(self.supports, g, lam)

    # ---------------------------------------------------------------- the equations ----
    def external(self, g, lam, tangent=True, loads=None):
        """Sum of the loads at (g, lam): (f (n, 6), node blocks (n, 6, 6) or None, element
        blocks (m, 4, 4, 6, 6) or None), the blocks being -df/d eta; ``loads``: a subset of the
        problem's loads to sum instead of all (linear analysis' reference stiffness)."""
        n = self.mesh.n_nodes
        f = np.zeros((n, 6))
        Kn = np.zeros((n, 6, 6)) if tangent else None
        Ke = None
        loads = self.loads if loads is None else list(loads)
        if not tangent:                       # the magnets' forces in one batch (magnets_force)
            mags = [ld for ld in loads if type(ld) is MagneticLoad]
            if len(mags) > 1:
                f += magnets_force(mags, g, lam)
                loads = [ld for ld in loads if type(ld) is not MagneticLoad]
        for load in loads:
            ev = load.evaluate(g, lam, tangent).checked(load, n, self.mesh.n_elements)
            f += ev.f
            if tangent and ev.node_blocks is not None:
                Kn += ev.node_blocks
            if tangent and ev.element_blocks is not None:
                if Ke is None:
                    Ke = np.zeros((self.mesh.n_elements, 4, 4, 6, 6))
                ids, blocks = ev.element_blocks
                if len(np.unique(ids)) == len(ids):
                    Ke[ids] += blocks
                else:                        # an element listed twice adds twice (as the compiled backend)
                    np.add.at(Ke, ids, blocks)
        return f, Kn, Ke

    def evaluate(self, g, lam, tangent=True, assembler=None, out=None, stress=None, loads=None, frame_loads=None):
        """The residual on the free dofs and, if asked, the tangent at (g, lam) (an
        :class:`Evaluation`); ``assembler``: another set of free dofs (default the problem's).

        With the numba backend and an element that has compiled kernels, the element and the
        loads write straight into the CSR data of the assembler's fixed pattern (``out``: a
        float64 data array of ``assembler.pattern().nnz`` to reuse, which the returned K then
        shares; another array is an OptionError);
        otherwise the NumPy path sums the blocks (the reference).  stress: a mixed element's
        independent stresses for the geometric part of the tangent (the mixed iteration).
        loads: a subset of the problem's loads to evaluate instead of all (on the NumPy path;
        linear analysis' reference stiffness without the loads' geometric stiffness).
        frame_loads: the problem's loads restated in the coordinates of g, one for one (a far
        part's iterate relative to its origin, ``solvers.origin.relocation``), evaluated in their
        place on either backend."""
        asm = assembler or self.assembler()
        if asm.mesh is not self.mesh and not (asm.mesh.n_nodes == self.mesh.n_nodes
                                              and np.array_equal(asm.mesh.quads, self.mesh.quads)):
            # its pattern and slots are another mesh's: K was assembled on the wrong node pairs
            # (75 % off on NumPy, 120 % on numba for 15 nodes in other quads, silently)
            raise MeshError(f"the assembler is of another mesh ({asm.mesh.n_nodes} nodes, {asm.mesh.n_elements} "
                            f"elements; this problem's: {self.mesh.n_nodes}, {self.mesh.n_elements}, or other quads): "
                            "build it on this problem's mesh, Assembler(problem.mesh, free)")
        g = _frames(g, self.mesh.n_nodes)
        if stress is not None and not self.element.mixed:
            raise OptionError(f"element {self.element_name!r} has no mixed iteration (stress=)")
        if stress is not None:
            stress = _per_row(stress, self.mesh.n_elements, 24, "element stresses", "element")
        if self.backend == "numba" and loads is None:
            if self._compiled is None:
                self._compiled = CompiledEvaluation(self)
            out_ev = self._compiled.evaluate(asm, g, lam, tangent, out, stress, frame_loads)
            if out_ev is not None:
                return out_ev
        if tangent and self.backend_setting == "auto":
            _backend.charge(self.mesh.n_elements)          # the 'auto' rule's count
        ev = (self.element.evaluate(g, tangent=tangent, stress=stress) if stress is not None
              else self.element.evaluate(g, tangent=tangent))
        loads = frame_loads if loads is None else loads
        fext, Kn_ext, Ke_ext = (self.external(g, lam, tangent=tangent) if loads is None       # the problem's loads
                                else self.external(g, lam, tangent=tangent, loads=loads))
        scale = force_scale_with_loads(ev.force_scale, self.loads if loads is None else loads, self.length_scale)
        out = Evaluation(asm.vector(ev.r - fext), ev.r, fext, scale, ev.energy,
                         stress=ev.stress, linearization=ev.linearization)
        if tangent:
            Ke = ev.element_blocks if Ke_ext is None else (
                Ke_ext if ev.element_blocks is None else ev.element_blocks + Ke_ext)
            Kn = Kn_ext if ev.node_blocks is None else ev.node_blocks + Kn_ext
            out.K = asm.matrix(Ke, ev.edge_blocks, Kn)
        return out

    def retract(self, g, eta):
        """The exponential update g_i exp(eta_i) of nodal frames g (n, 4, 4) by twists eta
        (n, 6) (the paper's Algorithm 1); compiled with the numba backend.  A MeshError when the
        shapes do not match.

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import Material, Problem, mesh
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1.0, 0.3, 0.1))
        >>> eta = np.tile([0.1, 0.0, 0.0, 0.0, 0.0, np.pi / 2], (4, 1))
        >>> np.round(p.retract(p.mesh.g0, eta)[0, :3, 0], 12).tolist()
        [0.0, 1.0, 0.0]
        """
        g, eta = np.asarray(g, dtype=float), np.asarray(eta, dtype=float)
        if g.ndim != 3 or g.shape[1:] != (4, 4) or eta.shape != (len(g), 6):
            raise MeshError(f"retract: frames of shape {g.shape} and increments of shape {eta.shape}; give k frames "
                            "(k, 4, 4) and one twist (v, w) per frame, (k, 6) (the compiled update reads eta[i] for "
                            "every frame i, past the end of a shorter eta)")
        if self.backend == "numba":
            from ..kernels.lie import retract
            out = np.empty_like(g, dtype=float)
            retract(np.ascontiguousarray(g, dtype=float), np.ascontiguousarray(eta, dtype=float), out)
            return out
        return g @ lie.exp(eta)

    def linear_stress(self, ev, eta):
        """A mixed element's stresses linearised about the state of the Evaluation ``ev``
        (with the tangent) for the nodal increments eta (n, 6) (``fem.Element.linear_stress``).

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import Material, Problem, mesh
        >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1.0e3, 0.0, 0.1))
        >>> eta = np.zeros((6, 6)); eta[[2, 5], 0] = 1e-2      # stretch the right column by 1 %
        >>> f = p.linear_stress(p.evaluate(p.mesh.g0, 0.0), eta)
        >>> round(float(f[1, 6]), 9)                            # N = E h eps on the right element
        1.0
        """
        eta = _per_row(eta, self.mesh.n_nodes, 6, "increments eta", "node")
        lin = ev.linearization
        if callable(lin):
            return lin(eta)
        return self.element.linear_stress(ev, eta)

    def residual(self, g, lam, assembler=None):
        """Free residual r_int - f_ext at (g, lam)."""
        return self.evaluate(g, lam, tangent=False, assembler=assembler).r

    def tangent(self, g, lam, assembler=None):
        """Assembled sparse tangent on the free dofs at (g, lam)."""
        return self.evaluate(g, lam, tangent=True, assembler=assembler).K

    # ---------------------------------------------------------------- solving ----------
    def solve(self, steps=None, control=None, solver=None, **options):
        """Solve the problem; returns a :class:`~core_se3.results.Result`.

        Parameters
        ----------
        steps : int, optional
            Number of equal load steps from lam_start to lam_end (load control).  Default: the
            problem's own settings (``solve_defaults``, a scenario's ``[solver] steps``), else 10.
        control : str, optional
            'load' (``solvers.newton_solve``), 'arclength', 'displacement' or 'linear' (:meth:`solve_linear`).
        solver : str, optional
            'serial' or 'distributed' (load stepping over the MPI ranks, :mod:`core_se3.parallel`).
            Default: 'distributed' for load control under ``mpirun -n N`` with N > 1, else
            'serial'; other controls run serially on every rank.
        **options
            Passed to the solver: the fields of ``core_se3.solvers.NewtonOptions`` (rtol, dtol,
            max_iter, max_cutbacks, ...) and its own keywords (lam_end, load_factors, g_init:
            frames, or a StepResult to continue with its probes' unwrapped rotations, ...).
            Keys given here override ``solve_defaults``.  With control 'linear', steps other
            than 1 and Newton options given here (not in ``solve_defaults``) are not used: an
            :class:`~core_se3.errors.OptionWarning` names them.
        """
        kw = dict(self.solve_defaults)
        kw.update(options)
        if steps is not None:
            kw["steps"] = steps
        control = control or kw.pop("control", "load")
        kw.pop("control", None)
        given = [*(["steps"] if steps is not None else []), *options]     # unused ones warn (OptionWarning)
        return dispatch(self, control, solver or kw.pop("solver", None), kw, given)

    solve_linear = solve_linear            # linear analysis (model.solving.solve_linear)


def _names(where):
    """True for a list or tuple of names (a union of named lines)."""
    return isinstance(where, (list, tuple)) and len(where) > 0 and all(isinstance(w, str) for w in where)
