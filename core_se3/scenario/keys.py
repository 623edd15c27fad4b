"""Dotted keys of scenario documents (``loads[0].force``, ``fields.coil.B[2]``): parsing, and
the check that a key to override or sweep exists (with the closest name)."""
from __future__ import annotations

import re

from ..errors import ScenarioError, did_you_mean

__all__ = ["split_dotted", "check_key", "repeated_value"]

_PART = re.compile(r"^([^.\[\]]+)((?:\[\d+\])*)$")


def split_dotted(key, file=None):
    """The parts of a dotted key: ``"loads[0].force"`` -> ``['loads', 0, 'force']``.

    Example
    -------
    >>> split_dotted("fields.coil.B[2]")
    ['fields', 'coil', 'B', 2]
    """
    parts = []
    for seg in str(key).split("."):
        m = _PART.match(seg)
        if not m:
            raise ScenarioError(f"cannot read the override key {key!r} (expected a.b[0].c)", file, key)
        parts.append(m.group(1))
        parts.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return parts



def check_key(raw, key, file=None):
    """ScenarioError unless every table and list entry on the way to the dotted ``key`` exists
    in the document (the last part may be a key the section takes; [solver] and [output] may
    be missing); names the closest one.

    Example
    -------
    >>> check_key({"fields": {"coil": {"B": [0, 0, 1]}}}, "fields.coli.B")
    Traceback (most recent call last):
    ...
    core_se3.errors.ScenarioError: [fields.coli.B]: the key 'fields.coli.B' refers to 'fields.coli', which the scenario does not have; did you mean 'coil'?; it has: coil
    """
    node, path = raw, ""
    parts = split_dotted(key, file)
    for i, p in enumerate(parts[:-1]):
        here = f"{path}.{p}" if path and not isinstance(p, int) else (f"{path}[{p}]" if isinstance(p, int) else p)
        if isinstance(p, int):
            if not isinstance(node, list) or p >= len(node):
                n = len(node) if isinstance(node, list) else 0
                raise ScenarioError(f"the key {key!r} refers to {here}, but the scenario has {n} entries "
                                    f"there", file, key)
        elif not isinstance(node, dict) or p not in node:
            if i == 0 and p in ("solver", "output"):
                return
            choices = list(node) if isinstance(node, dict) else []
            raise ScenarioError(f"the key {key!r} refers to {here!r}, which the scenario does not "
                                f"have{did_you_mean(p, choices)}; it has: {', '.join(map(str, choices)) or 'nothing'}",
                                file, key)
        node = node[p]
        path = here


def repeated_value(values):
    """Why a sweep's values of one key repeat one (``1e6,1e6``, ``8,8.0``: two identical runs,
    most likely a typo for another value), or '' when each is given once.

    Example
    -------
    >>> repeated_value([1e6, 2e6]), repeated_value([8, 16, 8.0])
    ('', 'lists 8.0 twice (values 0 and 2): the two runs would be the same; give each value once')
    """
    for j, b in enumerate(values):
        for i in range(j):
            if values[i] == b and isinstance(values[i], bool) == isinstance(b, bool):     # (1 and true differ)
                return f"lists {b!r} twice (values {i} and {j}): the two runs would be the same; give each value once"
    return ""
