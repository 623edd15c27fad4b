"""Registries of extension points (elements, load kinds, field kinds, catalogue cases and
families): a dict by name that refuses a second entry of the same name and answers an unknown
name with the closest one.

Example
-------
>>> reg = Registry("load kind")
>>> reg.register("gravity", object) is object
True
>>> reg.lookup("gravty")
Traceback (most recent call last):
...
core_se3.errors.OptionError: unknown load kind 'gravty'; did you mean 'gravity'?; registered: gravity
"""
from __future__ import annotations

from .errors import OptionError, did_you_mean

__all__ = ["Registry"]


class Registry(dict):
    """name -> entry, for the extension point ``what`` (used in messages)."""

    def __init__(self, what):
        super().__init__()
        self.what = what

    def register(self, name, entry):
        """Add ``entry`` under ``name`` (which must be a new, non-empty string); returns it."""
        if not isinstance(name, str) or not name:
            raise TypeError(f"a {self.what} needs a non-empty name, got {name!r}")
        if name in self:
            raise ValueError(f"{self.what} {name!r} is registered twice")
        self[name] = entry
        return entry

    def lookup(self, name):
        """The entry ``name``; an OptionError naming the closest registered name otherwise."""
        try:
            return self[name]
        except (KeyError, TypeError):
            raise OptionError(f"unknown {self.what} {name!r}{did_you_mean(name, self)}; registered: "
                              f"{', '.join(sorted(self))}") from None
