"""The element extension point: the :class:`Element` base class, what its evaluation returns
(:class:`ElementEvaluation`), and the registry that every front end reads.

An element turns the nodal frames g (n, 4, 4) into the internal nodal forces r (n, 6) (left
trivialised: one wrench per node in its body frame, r_i = dPi/d eta_i along g_i <- g_i exp(eta_i))
and, if asked, the blocks of their derivative along the same update.  Blocks come in three
shapes, summed by the assembler into the sparse tangent:

* ``element_blocks`` (m, 4, 4, 6, 6): node pairs (a, b) of each quad,
* ``edge_blocks`` (E, 2, 2, 6, 6): node pairs of each mesh edge (``mesh.edge_nodes``),
* ``node_blocks`` (n, 6, 6): one block per node.

A new element is one file: a subclass of :class:`Element` decorated with
:func:`register_element`; the Python API (``Problem(..., element=NAME)``), scenario files
(``[solver] element``) and the command line (``--element``) then accept its name.

Example
-------
>>> from core_se3 import fem
>>> sorted(fem.ELEMENTS)
['default', 'seed']
"""
from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..registry import Registry

__all__ = ["Element", "ElementEvaluation", "ELEMENTS", "register_element", "make_element"]


@dataclass
class ElementEvaluation:
    """Internal forces and (optionally) tangent blocks of all elements at one state.

    energy: the elastic energy [force x length]; r: (n, 6) internal nodal forces (body frames);
    force_scale: the size of the terms that cancel in r (its round-off floor, used by the
    convergence test); the blocks as in the module docstring (None = none of that shape).

    Attributes
    ----------
    energy : float
        Elastic energy [force x length].
    r : (n, 6) ndarray
        Internal generalised nodal forces dPi/d eta_i: force [force] and moment [force x length]
        in each node's body frame.
    force_scale : float
        Size of the terms that cancel in r [force] (round-off floor of the residual).
    element_blocks : (m, 4, 4, 6, 6) ndarray or None
        Tangent blocks of the node pairs of each quad.
    edge_blocks : (E, 2, 2, 6, 6) ndarray or None
        Tangent blocks of the node pairs of each mesh edge.
    node_blocks : (n, 6, 6) ndarray or None
        Tangent blocks of single nodes.
    stress : ndarray or None
        The element's stress variables at this state (a mixed element, see :attr:`Element.mixed`;
        the default element: Dbar (z - z0) (m, 24)).
    linearization : object
        What a mixed element's ``linear_stress`` needs from this state.

    Example
    -------
    >>> from core_se3 import mesh, Material, fem
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> el = fem.make_element("default", m, Material(1.0e3, 0.0, 0.01))
    >>> g = m.g0.copy(); g[:, 0, 3] *= 1.01              # uniform stretch, strain 0.01
    >>> ev = el.evaluate(g, tangent=False)
    >>> round(float(ev.energy), 12), ev.element_blocks    # 1/2 E h eps^2 x area 1
    (0.0005, None)
    """
    energy: float
    r: np.ndarray
    force_scale: float
    element_blocks: np.ndarray | None = None
    edge_blocks: np.ndarray | None = None
    node_blocks: np.ndarray | None = None
    stress: np.ndarray | None = None
    linearization: object = None


class Element(abc.ABC):
    """Base class of shell elements on a mesh with a material law.

    Subclasses set ``name`` and implement :meth:`evaluate` and :meth:`energy`.  An element
    whose strain is a state updated by the increments (``stateful = True``, e.g. the seed's
    incremental twist) implements :meth:`save`, :meth:`restore` and :meth:`update`; the solvers
    call them around every Newton step, and path following refuses it.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The reference mesh.
    material : core_se3.fem.ResultantLaw
        A :class:`Material` or :class:`RegionMaterial`.

    Attributes
    ----------
    name : str
        The registry key (class attribute); ``Problem(..., element=name)`` selects the element.
    stateful : bool
        True if the strain is a state carried between Newton steps (class attribute).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh, Material
    >>> class NoStiffness(Element):           # a (useless) element: zero energy, zero forces
    ...     name = "none"
    ...     def evaluate(self, g, tangent=True):
    ...         return ElementEvaluation(0.0, np.zeros((len(g), 6)), 0.0)
    ...     def energy(self, g):
    ...         return 0.0
    >>> el = NoStiffness(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> el.evaluate(el.mesh.g0).r.shape, el.stateful, el.cell_fields(el.mesh.g0)
    ((6, 6), False, {})
    """

    name: ClassVar[str] = ""
    stateful: ClassVar[bool] = False
    #: True when the element supports the mixed (MIP) Newton iteration: ``evaluate`` accepts
    #: ``stress=`` (independent stresses for the geometric part of the tangent) and
    #: :meth:`linear_stress` updates them (``solvers.newton``, NewtonOptions.iteration)
    mixed: ClassVar[bool] = False

    def __init__(self, mesh, material):
        self.mesh = mesh
        self.material = material
        X = mesh.X[mesh.quads]                                 # (m, 4, 3) reference corners
        #: the longest reference edge of every element (m,) [length]: the size a mesh-dependent
        #: law sees (``Material.shear_stabilisation``)
        self.size = np.linalg.norm(X - np.roll(X, -1, axis=1), axis=2).max(axis=1)

    @abc.abstractmethod
    def evaluate(self, g, tangent=True) -> ElementEvaluation:
        """Internal forces at the frames g (n, 4, 4), with the tangent blocks if ``tangent``
        (a mixed element also takes ``stress=``, see :attr:`mixed`)."""

    def linear_stress(self, ev, eta):
        """A mixed element's stresses linearised about the state of ``ev`` (an evaluation
        with the tangent) for the nodal increments eta (n, 6)."""
        raise NotImplementedError(f"element {self.name!r} has no mixed iteration")

    @abc.abstractmethod
    def energy(self, g) -> float:
        """Elastic energy at the frames g."""

    def cell_fields(self, g, increments=None) -> dict:
        """Per-element output fields (name -> (m, k)) for VTU files; none by default.
        ``increments``: a linear analysis' nodal increments (n, 6) about the reference, whose
        state g is (its fields are then the linear ones)."""
        return {}

    def compiled(self, pattern):
        """The element's compiled kernels on a ``kernels.Pattern`` (an object with
        ``residual(g)`` and ``tangent(g, data)``), or None: then the compiled backend evaluates
        this element with :meth:`evaluate` and scatters its blocks."""
        return None

    # state of a stateful element (no-ops for the path-independent ones)
    def save(self):
        """Remember the current state (before a Newton step)."""

    def restore(self):
        """Return to the saved state (after a failed Newton step)."""

    def update(self, eta):
        """Advance the state by the nodal increments eta (n, 6)."""


ELEMENTS = Registry("element")


def register_element(cls):
    """Class decorator: make an Element subclass available under ``cls.name``.

    Parameters
    ----------
    cls : type
        A subclass of :class:`Element` with a new, non-empty ``name``.

    Returns
    -------
    type
        ``cls`` itself (so it works as a decorator).  A TypeError for anything but an Element
        subclass, a ValueError for a name that is already registered.

    Example
    -------
    >>> from core_se3.fem import DefaultElement
    >>> register_element(DefaultElement)
    Traceback (most recent call last):
    ...
    ValueError: element 'default' is registered twice
    """
    if not (isinstance(cls, type) and issubclass(cls, Element)):
        raise TypeError("register_element needs an Element subclass")
    return ELEMENTS.register(cls.name, cls)


def make_element(name, mesh, material) -> Element:
    """The element ``name`` (a key of ELEMENTS) on ``mesh`` with ``material``.

    Parameters
    ----------
    name : str
        A registered element name ('default', 'seed', or one of :func:`register_element`).
    mesh : core_se3.mesh.Mesh
        The reference mesh.
    material : core_se3.fem.ResultantLaw
        The resultant law.

    Returns
    -------
    Element
        The element, with its reference data computed.  An unknown name raises
        :class:`~core_se3.errors.OptionError` naming the closest one.

    Example
    -------
    >>> from core_se3 import mesh, Material
    >>> type(make_element("seed", mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))).__name__
    'SeedElement'
    """
    return ELEMENTS.lookup(name)(mesh, material)
