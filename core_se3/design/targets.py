"""What a design asks and what it returns: :class:`Target` (the misfit of a quantity),
:class:`Pose` (targets and fixed settings of one pose), :class:`Smoothness` (regularisation)
and :class:`DesignResult` (see ``design.inverse``)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import DesignError
from .objectives import target_array

__all__ = ["Target", "Pose", "Smoothness", "DesignResult"]


class Target:
    """A target of a pose: the misfit of a quantity (``design.objectives``), optionally only some
    of its components and minus a ``value``, weighted by w / s^2.

    Parameters
    ----------
    quantity : Quantity
        The quantity (its own ``target`` already subtracted, or give ``value``).
    weight : float
        w >= 0.
    scale : float, optional
        s (default: the problem's length for positions, 1 for angles and other quantities).
    components : sequence of int, optional
        The components of the quantity that count (default all).
    value : array, optional
        Subtracted from those components.
    name : str, optional
        For reports (default the quantity's name).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import ProbePosition
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)); p.add_probe("tip", "x1")
    >>> t = Target(ProbePosition(p, "tip"), components=[2], value=[0.5])
    >>> t.misfit(p, p.mesh.g0, 1.0).tolist()
    [-0.5]
    """

    def __init__(self, quantity, weight=1.0, scale=None, components=None, value=None, name=None):
        if not (np.isfinite(weight) and weight >= 0):
            raise DesignError(f"target weight must be finite and >= 0, got {weight}")
        what = f"target {name or quantity.name!r}"
        self.quantity, self.weight = quantity, float(weight)
        if scale is not None and not (np.isfinite(scale) and scale > 0):
            raise DesignError(f"{what}: the scale of its misfit must be finite and > 0, got {scale}")
        self.scale = scale
        self.components = None if components is None else np.asarray(components).ravel()
        if self.components is not None and (self.components.size == 0 or self.components.dtype.kind not in "iu"
                                            or self.components.min() < 0 or self.components.max() >= quantity.size):
            raise DesignError(f"{what}: components {self.components.tolist()} must be one or more whole numbers in "
                              f"0 .. {quantity.size - 1}")
        n = quantity.size if self.components is None else len(self.components)
        self.value = np.zeros(n) if value is None else target_array(value, (n,), f"{what}: value")
        self.name = name or quantity.name
        self.size = n

    def resolve_scale(self, problem):
        if self.scale is None:
            from .objectives import NodePosition, ProbePosition
            self.scale = problem.length_scale if isinstance(self.quantity, (NodePosition, ProbePosition)) else 1.0
        return self.scale

    def misfit(self, problem, g, lam):
        """The misfit (size,) in the quantity's units."""
        q = self.quantity.value(problem, g, lam)
        return (q if self.components is None else q[self.components]) - self.value

    def rows(self):
        """Index of the misfit's components in the quantity."""
        return np.arange(self.quantity.size) if self.components is None else self.components


class Pose:
    """A pose: its targets, the fixed values of variables in this pose (``settings``:
    {variable: value}, e.g. the field of a pose at zero), and its load factor.

    Example
    -------
    >>> Pose("flat").lam
    1.0
    """

    def __init__(self, name, targets=(), settings=None, lam=1.0):
        self.name, self.targets, self.lam = str(name), list(targets), float(lam)
        self.settings = dict(settings or {})


class Smoothness:
    """Smoothness regularisation 1/2 alpha sum_j |x_(j+1) - x_j|^2 / scale^2 over the regions of a
    region variable (a magnetisation: neighbouring regions in the order given).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UniformField
    >>> from core_se3.design import RegionMagnetisation
    >>> p = Problem(mesh.rectangle(4.0, 0.5, 4, 1), Material(1e3, 0.0, 0.1))
    >>> _ = p.add_magnetic((0.2, 0.0, 0.0), UniformField((0.0, 0.0, 1.0)), mu0=1.0)
    >>> Smoothness(RegionMagnetisation(p, [[0, 1], [2, 3]]), 1e-3).D.shape
    (3, 6)
    """

    def __init__(self, variable, alpha):
        k = len(getattr(variable, "regions", []))
        if k < 2:
            raise DesignError("smoothness needs a variable over two or more regions")
        if not (np.isfinite(alpha) and alpha >= 0):
            raise DesignError(f"smoothness weight must be >= 0, got {alpha}")
        c = variable.size // k
        D = np.zeros(((k - 1) * c, variable.size))
        for j in range(k - 1):
            for i in range(c):
                D[j * c + i, j * c + i], D[j * c + i, (j + 1) * c + i] = -1.0, 1.0
        self.variable, self.alpha, self.D = variable, float(alpha), D


@dataclass
class DesignResult:
    """The outcome of :meth:`Design.optimise`.

    Attributes
    ----------
    success : bool
        The optimiser's own convergence flag; ``reached``: the largest misfit is within the
        ``tolerance`` (None without one); ``message``: says which, with the misfit.
    x : (nx,) ndarray
        The variables' components (``labels``); ``values``: name -> array per variable.
    objective : float
        Phi at x; ``gradient``: dPhi/dx; ``misfit``: pose -> target -> max |misfit|;
        ``max_misfit``: the largest.
    iterations, evaluations, equilibrium_solves, newton_iterations : int
        Counts; ``time`` [s]; ``history``: one dict per iteration (objective, gradient_norm,
        equilibrium_solves, ...); ``states``: the final EquilibriumState of every pose;
        ``idle``: the labels of the components without effect at the result (``Design.idle``);
        ``branch``: pose -> distance to the equilibrium a solve from flat reaches, where the
        design's is another (``Design.off_branch``); ``failed``: the trial points least_squares
        rejected because their equilibrium failed (x and the message), said in ``message``;
        ``rejected``: every trial point least_squares rejected (those, and those that did not
        decrease Phi; None for the other methods).  least_squares' ``iterations`` are the start
        and its accepted steps: with ``max_iter`` = N evaluations, N = iterations + rejected.

    Example
    -------
    >>> r = DesignResult(True, None, "ok", np.zeros(1), ["a"], {"a": np.zeros(1)}, 0.0, np.zeros(1), {}, 0.0)
    >>> r.document()["variables"]
    {'a': [0.0]}
    """
    success: bool
    reached: bool | None
    message: str
    x: np.ndarray
    labels: list
    values: dict
    objective: float
    gradient: np.ndarray
    misfit: dict
    max_misfit: float
    iterations: int = 0
    evaluations: int = 0
    equilibrium_solves: int = 0
    newton_iterations: int = 0
    time: float = 0.0
    method: str = ""
    history: list = field(default_factory=list)
    states: list = field(default_factory=list)
    idle: list = field(default_factory=list)
    branch: dict = field(default_factory=dict)
    failed: list = field(default_factory=list)
    rejected: int | None = None

    def document(self):
        """A JSON-able summary (no frames)."""
        return dict(success=bool(self.success), reached=self.reached, message=self.message, method=self.method,
                    variables={k: np.asarray(v).tolist() for k, v in self.values.items()},
                    components=dict(zip(self.labels, np.asarray(self.x).tolist())),
                    objective=float(self.objective), gradient=np.asarray(self.gradient).tolist(),
                    misfit=self.misfit, max_misfit=float(self.max_misfit), iterations=int(self.iterations),
                    evaluations=int(self.evaluations), equilibrium_solves=int(self.equilibrium_solves),
                    newton_iterations=int(self.newton_iterations), time=float(self.time), history=self.history,
                    idle=list(self.idle), branch=dict(self.branch), failed=list(self.failed),
                    rejected=self.rejected)
