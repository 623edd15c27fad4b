"""Exception hierarchy: every failure names its cause; nothing fails silently."""
from __future__ import annotations


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
