"""Exception hierarchy: every failure names its cause and the likely fix; nothing fails silently.

Every exception derives from :class:`CoreSE3Error`; the ones caused by invalid input also derive
from :class:`ValueError`.  :func:`did_you_mean` is the one helper that turns a misspelt name into
a suggestion, used by every message that rejects a name (keys, regions, edges, cases, elements,
fields, load kinds).

Example
-------
>>> from core_se3.errors import did_you_mean
>>> did_you_mean("plam", ["palm", "tips"])
"; did you mean 'palm'?"
"""
from __future__ import annotations

import difflib

__all__ = ["CoreSE3Error", "MaterialError", "MeshError", "LoadError", "SupportError",
           "SingularSystemError", "ConvergenceError", "ElementTooDistortedError", "ScenarioError",
           "CheckpointError", "OptionError", "did_you_mean"]


def did_you_mean(name, choices):
    """``"; did you mean 'X'?"`` for the closest of ``choices`` to ``name``, else ``""``.

    Case differences count as close (``br`` suggests ``Br``).
    """
    choices = [str(c) for c in choices]
    name = str(name)
    folded = {c.lower(): c for c in choices}
    if name.lower() in folded and folded[name.lower()] != name:
        return f"; did you mean {folded[name.lower()]!r}?"
    near = difflib.get_close_matches(name, choices, n=1)
    if not near:
        near = [folded[m] for m in difflib.get_close_matches(name.lower(), list(folded), n=1)]
    return f"; did you mean {near[0]!r}?" if near else ""


class CoreSE3Error(Exception):
    """Base class of all errors raised by core_se3."""


class MaterialError(CoreSE3Error, ValueError):
    """Invalid material parameters (E <= 0, nu outside (-1, 0.5), h <= 0, non-finite)."""


class MeshError(CoreSE3Error, ValueError):
    """Degenerate or inconsistent mesh (zero-area or inverted quads, bad connectivity, ...)."""


class LoadError(CoreSE3Error, ValueError):
    """Invalid load specification (NaN or infinite values, unknown edge, bad direction)."""


class SupportError(CoreSE3Error, ValueError):
    """Invalid support specification (unknown edge or node, conflicting constraints)."""


class OptionError(CoreSE3Error, ValueError):
    """An unknown name (element, load kind, field, linear solver, ...) or an invalid solver
    option (steps < 1, non-finite load factors, ...)."""


class SingularSystemError(CoreSE3Error):
    """The tangent is singular: usually a missing support (rigid-body motion left free)."""


class ConvergenceError(CoreSE3Error):
    """Newton failed even after the allowed step cut-backs.

    ``result`` keeps every load step that converged before the failure.
    """

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class ElementTooDistortedError(CoreSE3Error):
    """A relative rotation across an element edge reached pi, where the logarithm is cut."""


class ScenarioError(CoreSE3Error, ValueError):
    """An invalid scenario file: ``file`` and dotted ``key`` name where, the message what was
    expected and what was found."""

    def __init__(self, message, file=None, key=None):
        self.file = file
        self.key = key
        where = ": ".join(x for x in (file, f"[{key}]" if key else None) if x)
        super().__init__(f"{where}: {message}" if where else message)
        self.detail = message


class CheckpointError(CoreSE3Error):
    """A checkpoint that is missing, unreadable or belongs to another scenario."""
