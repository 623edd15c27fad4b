"""User kinds from the command line and from scenario files: a scenario's
``plugins = ["my_kinds.py", "package.module"]`` (files relative to the scenario, or importable
modules) and ``core-se3 run/sweep/design --plugin FILE`` import the user's registrations
(``core_se3.register(...)``, ``register_load(...)``, ...) before the scenario is validated, so
that its kinds are accepted like the built-in ones (docs/EXTENDING.md).

A file is imported once per process (by its absolute path; a scenario run again, a sweep or a
resume finds its kinds registered); its SHA-256 is part of the scenario's fingerprint, so that
``--resume`` refuses a checkpoint made with another version of the plugin.  A plugin is Python
code run with the user's rights, like any script: run only plugins you trust.

Example
-------
>>> import pathlib, tempfile
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> _ = (d / "kinds.py").write_text("X = 1\\n")
>>> [name for name, digest in load_plugins(["kinds.py"], str(d))]
['kinds.py']
>>> load_plugins(["missing.py"], str(d))                      # doctest: +ELLIPSIS
Traceback (most recent call last):
...
core_se3.errors.ScenarioError: [plugins[0]]: plugin file 'missing.py' does not exist (looked for .../missing.py)
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import sys
import traceback

from ..errors import ScenarioError

__all__ = ["load_plugins", "is_file_name", "LOADED"]

LOADED = {}          # absolute path or module name -> SHA-256 of its source (one import per process)


def is_file_name(name):
    """True for a plugin given as a file (``*.py`` or a path), False for a module name.

    Example
    -------
    >>> is_file_name("kinds/torus.py"), is_file_name("mypkg.kinds")
    (True, False)
    """
    return name.endswith(".py") or "/" in name or os.sep in name


def load_plugins(names, base_dir=".", file=None, key="plugins"):
    """Import the plugins ``names`` (files relative to ``base_dir``, or module names) once each;
    returns [(name, sha256 of its source)].  A plugin that is missing, fails to import or
    registers a kind twice is a ScenarioError naming ``key[i]`` and what went wrong (with the
    line of the plugin that raised)."""
    out = []
    for i, name in enumerate(names):
        where = f"{key}[{i}]"
        if not isinstance(name, str) or not name:
            raise ScenarioError(f"expected the name of a plugin file or module, got {name!r}", file, where)
        if is_file_name(name):
            path = os.path.abspath(name if os.path.isabs(name) else os.path.join(base_dir, name))
            if not os.path.isfile(path):
                raise ScenarioError(f"plugin file {name!r} does not exist (looked for {path})", file, where)
            out.append((name, _import_file(path, name, file, where)))
        else:
            out.append((name, _import_module(name, file, where)))
    return out


def _digest(path):
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def _import_file(path, name, file, where):
    if path in LOADED:
        return LOADED[path]
    digest = _digest(path)
    modname = f"core_se3_plugin_{os.path.splitext(os.path.basename(path))[0]}_{digest[:12]}"
    spec = importlib.util.spec_from_file_location(modname, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[modname] = module
    try:
        spec.loader.exec_module(module)
    except BaseException as exc:
        sys.modules.pop(modname, None)
        if isinstance(exc, (KeyboardInterrupt, SystemExit)):
            raise
        raise ScenarioError(f"plugin {name!r} failed to import: {_what(exc, path)}", file, where) from None
    LOADED[path] = digest
    return digest


def _import_module(name, file, where):
    if name in LOADED:
        return LOADED[name]
    try:
        module = importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name and name.startswith(exc.name):
            raise ScenarioError(f"plugin module {name!r} is not importable (no module {exc.name!r} on the "
                                "Python path); give a file name ending in .py for a file", file, where) from None
        raise ScenarioError(f"plugin {name!r} failed to import: {_what(exc, None)}", file, where) from None
    except Exception as exc:
        raise ScenarioError(f"plugin {name!r} failed to import: {_what(exc, None)}", file, where) from None
    src = getattr(module, "__file__", None)
    digest = _digest(src) if src and os.path.isfile(src) else hashlib.sha256(name.encode()).hexdigest()
    LOADED[name] = digest
    return digest


def _what(exc, path):
    """``Type: message`` and the plugin's line that raised it (the last frame in its file)."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if path is None or os.path.abspath(f.filename) == path]
    if isinstance(exc, SyntaxError) and exc.lineno:
        return f"SyntaxError at line {exc.lineno}: {exc.msg}"
    at = f" (line {frames[-1].lineno}: {frames[-1].line})" if frames else ""
    return f"{type(exc).__name__}: {exc}{at}"
