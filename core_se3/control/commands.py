"""The commands of a control session: its design variables by name (``design.variables``:
field components, magnetisation per region, load magnitudes, E or h per region), checked once
for duplicate names and for two variables that set the same thing, and the values of an update
checked against them (size, finite, bounds) before anything is assigned.

Example
-------
>>> from core_se3 import Problem, Material, mesh
>>> from core_se3.model import UniformField
>>> from core_se3.design import FieldVariable
>>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
>>> f = UniformField((0.0, 0.0, 0.5)); _ = p.add_magnetic((1.0, 0.0, 0.0), f, mu0=1.0)
>>> cmd = Commands([FieldVariable(p, f, name="coil")])
>>> cmd.parse({"coil": [0.0, 0.0, 0.6]})["coil"].tolist()
[0.0, 0.0, 0.6]
>>> cmd.parse({"cole": 1.0})
Traceback (most recent call last):
...
core_se3.errors.OptionError: unknown variable 'cole'; did you mean 'coil'?; the session's variables: coil
"""
from __future__ import annotations

import numpy as np

from ..design import (FieldGradientVariable, FieldVariable, LoadMagnitude, MaterialVariable, RegionMagnetisation,
                      Variable, magnetic_loads)
from ..errors import OptionError, did_you_mean, warn_angle
from ..model import GradientField, UniformField

__all__ = ["Commands", "scenario_variables", "as_numbers"]


def _sets(v):
    """What a variable sets: (kind, object id) pairs; two variables sharing one conflict."""
    if isinstance(v, FieldVariable):
        return [("field", id(v.field))]
    if isinstance(v, FieldGradientVariable):
        return [("gradient", id(v.field))]
    if isinstance(v, LoadMagnitude):
        return [("load", id(ld)) for ld in v.loads]
    if isinstance(v, RegionMagnetisation):
        return [("magnet", id(ld)) for ld, _, _ in v.loads]
    if isinstance(v, MaterialVariable):
        return [("material " + v.prop, int(e)) for r in v.regions for e in r]
    return [("variable", id(v))]


class Commands:
    """The named variables of a session (module docstring).

    Parameters
    ----------
    variables : sequence of core_se3.design.Variable
        Each with a unique ``name`` other than ``lam`` (the load factor's keyword of
        ``Session.update``); no two may set the same field, load, magnet or element property
        (OptionError naming both).
    problem : core_se3.Problem, optional
        The session's problem: a variable made on another is refused (:meth:`check`).

    Attributes
    ----------
    variables : dict
        name -> Variable, in the order given.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import LoadMagnitude
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> Commands([LoadMagnitude(p, p.loads[0], name="P")]).values()["P"].tolist()
    [1.0]
    """

    def __init__(self, variables, problem=None):
        self.variables, self.problem = {}, problem
        owner = {}
        for v in variables:
            self.check(v)
            if v.name in self.variables:
                raise OptionError(f"two variables are named {v.name!r}: give each its own name (name=...; in a "
                                  f"scenario rename [fields.{v.name}]: its [[loads]] entries are load0, load1, ...)")
            if v.name == "lam":
                # Session.update(lam=...) is the load factor: the variable could never be commanded
                raise OptionError("a variable cannot be named 'lam': update(lam=...) sets the load factor, so its "
                                  "commands would move the load factor instead; give it another name (name=..., "
                                  "or rename the scenario's [fields.lam])")
            for key in _sets(v):
                if key in owner:
                    raise OptionError(f"variables {owner[key]!r} and {v.name!r} set the same {key[0]}: a command "
                                      "could give it two values; keep one of them")
                owner[key] = v.name
            self.variables[v.name] = v

    def check(self, v):
        """OptionError unless v is a design variable of the session's problem: one made on another
        Problem sets nothing the session solves (before, its command was refused as 'the path
        turns sharply', and its Jacobian was that of the other problem's load, not zero)."""
        if not isinstance(v, Variable):
            raise OptionError(f"a session's variables are core_se3.design variables, got {type(v).__name__}")
        if self.problem is not None and getattr(v, "problem", self.problem) is not self.problem:
            raise OptionError(f"the variable {v.name!r} was made on another Problem than the session's: make it on "
                              "the session's problem (session.problem)")

    def values(self):
        """name -> the current values (size,) of every variable."""
        return {k: v.value() for k, v in self.variables.items()}

    def lookup(self, name):
        """The variable of a name, or OptionError with the closest one."""
        try:
            return self.variables[name]
        except KeyError:
            raise OptionError(f"unknown variable {name!r}{did_you_mean(name, self.variables)}; the session's "
                              f"variables: {', '.join(self.variables) or 'none'}") from None

    def pick(self, variables=None):
        """The variables named by ``variables``: None (all), one name or variable, or a sequence
        of them (a string is one name: before, a loop's variables="PB" commanded P and B); a
        variable object must be one of these (OptionError otherwise).

        Example
        -------
        >>> from core_se3 import Problem, Material, mesh
        >>> from core_se3.design import LoadMagnitude
        >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
        >>> p.add_edge_force("x1", (0.0, 0.0, 1.0))
        >>> [v.name for v in Commands([LoadMagnitude(p, p.loads[0], name="P")]).pick("P")]
        ['P']
        """
        if variables is None:
            return list(self.variables.values())
        items = [variables] if isinstance(variables, (str, Variable)) else list(variables)
        out = []
        for v in items:
            mine = self.lookup(v.name if isinstance(v, Variable) else v)
            if isinstance(v, Variable) and v is not mine:
                raise OptionError(f"the variable {v.name!r} given is not the session's variable of that name; pass "
                                  "its name")
            out.append(mine)
        return out

    def parse(self, values):
        """name -> (size,) arrays of the commanded values, checked (OptionError: unknown name,
        wrong size, not finite, outside the bounds or a norm bound)."""
        out = {}
        for name, x in values.items():
            v = self.lookup(name)
            a = as_numbers(x)
            if a is None:                # a bool, a string or None is no command: not read as 1, 2.0, nan
                raise OptionError(f"variable {name!r}: expected {v.size} number{'s' * (v.size > 1)}, got {x!r}")
            a = a.ravel()
            if a.size != v.size:
                raise OptionError(f"variable {name!r} has {v.size} components ({', '.join(v.labels)}), got {a.size}")
            _check_shape(v, np.shape(x))
            if not np.all(np.isfinite(a)):
                raise OptionError(f"variable {name!r}: the command {a.tolist()} is not finite")
            for lab, x in zip(v.labels, a):              # a polar form's angle [rad]: degrees?
                if lab.endswith(".angle"):
                    warn_angle(x, f"the command {lab}")
            bad = (a < v.lower) | (a > v.upper)
            if np.any(bad):
                i = int(np.nonzero(bad)[0][0])
                raise OptionError(f"variable {v.labels[i]!r}: the command {a[i]:g} lies outside its bounds "
                                  f"[{v.lower[i]:g}, {v.upper[i]:g}]")
            for idx, top in v.norm_bounds:
                if np.linalg.norm(a[idx]) > top * (1 + 1e-12):
                    raise OptionError(f"variable {name!r}: the command has norm {np.linalg.norm(a[idx]):g} above "
                                      f"its bound {top:g}")
            out[name] = a
        return out

    def assign(self, values, problem=None, g=None, lam=None):
        """Assign name -> values (already parsed) to the variables.  With ``problem``, ``g`` and
        ``lam``: return the exact change of the free residual at (g, lam) that the assignment
        makes, or None when a variable changes in which the residual is not linear (module
        docstring of ``control.corrector``: the predictor's right-hand side without a residual
        evaluation)."""
        dr = None if problem is None else np.zeros((problem.mesh.n_nodes, 6))
        for name, x in values.items():
            v = self.variables[name]
            if dr is not None:
                # one variable at a time, at the others' current values: r is linear in each
                # (the magnetic load is bilinear in field and dipoles), so the sum is exact
                d = _linear_change(v, problem, g, lam, np.asarray(x, float))
                dr = None if d is None else dr + d
            v.assign(x)
        return None if dr is None else problem.assembler().vector(dr)


def as_numbers(x):
    """x as a float array when every entry is a number (integer or real), else None: a bool, a
    string, None or a complex number is no number here (before, np.asarray read True as 1.0 and
    '2' as 2.0).  NumPy makes [0, 0, True] an integer array: the entries themselves are looked at.

    Example
    -------
    >>> as_numbers([1, 2.5]).tolist(), as_numbers([0.0, True]), as_numbers([["1"]])
    ([1.0, 2.5], None, None)
    """
    try:
        kind = np.asarray(x).dtype.kind
        a = np.asarray(x, float)
        if not isinstance(x, np.ndarray) and any(isinstance(e, (bool, np.bool_))
                                                 for e in np.asarray(x, dtype=object).ravel()):
            kind = "b"
    except (TypeError, ValueError):
        return None
    return a if kind in "iuf" else None


def _check_shape(v, shape):
    """OptionError for a command array of more than one axis (beyond axes of length 1) whose shape
    is not the variable's own -- (regions, components) of a magnetisation: its entries would be
    read in another order (before, a magnetisation of two regions given as (3, 2), components by
    regions, set region 0 to (1, 1, 0) for (1, 0, 0.1) and (1, 0, -0.1))."""
    own = (len(v.regions), len(v.free)) if isinstance(v, RegionMagnetisation) else (v.size,)
    axes = tuple(n for n in shape if n != 1)
    if len(axes) > 1 and axes != tuple(n for n in own if n != 1):
        raise OptionError(f"variable {v.name!r}: a command of shape {tuple(shape)} is read in the order of its "
                          f"components ({', '.join(v.labels)}); give that flat list or an array of shape {own}")


def _linear_change(v, problem, g, lam, x):
    """r(g; v = x) - r(g; v now) (n, 6) for a variable in which r is linear, else None."""
    if isinstance(v, FieldVariable):                      # linear in the field vector
        full = v.full.copy()
        full[v.free] = x
        return np.einsum("nik,k->ni", v.dr_dB(problem, g, lam), v.vector(full) - v.vector())
    if isinstance(v, RegionMagnetisation):                # linear in B^r per region
        full = v.full.copy()
        full[:, v.free] = x.reshape(len(v.regions), len(v.free))
        return np.einsum("nijk,jk->ni", v.dr_dBr(problem, g, lam), v.Br(full) - v.Br())
    if isinstance(v, (LoadMagnitude, FieldGradientVariable)):
        return np.einsum("nik,k->ni", v.dr_dp(problem, g, lam), x - v.value())
    return None


def scenario_variables(scn):
    """The default variables of a scenario's session: every uniform (or uniform-gradient) field
    that magnets feel, as its vector (``FieldVariable``, named by the field: ``coil`` for
    [fields.coil]), and every [[loads]] entry of scaled loads as its magnitude (``LoadMagnitude``,
    ``load0``, ``load1``, ... after the entries; one multiplier for all the loads an entry built:
    an edge load on a union of lines, gravity on several densities or thicknesses).

    Example
    -------
    >>> from core_se3 import scenario
    >>> scn = scenario.loads('''
    ... units = "N-mm-MPa"
    ... [mesh]
    ... generator = "rectangle"
    ... L = 20.0
    ... width = 5.0
    ... nx = 4
    ... ny = 1
    ... [material]
    ... E = 1.0
    ... nu = 0.3
    ... h = 0.5
    ... [[supports]]
    ... type = "clamp"
    ... edge = "x0"
    ... [fields.coil]
    ... type = "uniform"
    ... B = [0.0, 0.0, 0.01]
    ... [[magnets]]
    ... Br = [0.01, 0.0, 0.0]
    ... [[loads]]
    ... type = "edge_force"
    ... edge = "x1"
    ... force = [0.0, 0.0, 1e-4]
    ... ''')
    >>> [v.name for v in scenario_variables(scn)]
    ['coil', 'load0']
    """
    prob, out = scn.problem, []
    for name, f in scn.fields.items():
        uniform = isinstance(f, UniformField) and f.direction is None
        if (uniform or isinstance(f, GradientField)) and magnetic_loads(prob, f):
            out.append(FieldVariable(prob, f, "vector", name=name))
    for i, built in enumerate(scn.load_objects):      # an entry of several loads (an edge load on a
        if built and all(callable(getattr(ld, "scale", None)) for ld in built):     # union of lines) is one
            out.append(LoadMagnitude(prob, built if len(built) > 1 else built[0], name=f"load{i}"))
    return out
