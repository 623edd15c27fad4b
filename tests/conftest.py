"""Test markers and DOLFINx gating.

* Tests in modules named ``test_fenicsx*`` get the ``dolfinx`` marker; all others get ``core``.
* ``test_fenicsx*`` modules are only left out of collection when ``CORE_ONLY=1`` is set AND
  ``import dolfinx`` fails (the NumPy-2 run of ``.ci/run``). Otherwise they are collected, so in the
  Debian run a missing/broken DOLFINx makes them FAIL loudly instead of being skipped.
"""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import pytest

_DOLFINX_PREFIX = "test_fenicsx"


def _core_only() -> bool:
    return os.environ.get("CORE_ONLY", "") == "1"


_dolfinx_ok: bool | None = None


def _dolfinx_importable() -> bool:
    global _dolfinx_ok
    if _dolfinx_ok is None:
        import importlib.util

        if importlib.util.find_spec("dolfinx") is None:  # not installed: do not touch it at all
            _dolfinx_ok = False
        else:
            try:
                import dolfinx  # noqa: F401
            except Exception:
                _dolfinx_ok = False
            else:
                _dolfinx_ok = True
    return _dolfinx_ok


def pytest_ignore_collect(collection_path: Path, config):  # pytest >= 7
    if collection_path.name.startswith(_DOLFINX_PREFIX) and collection_path.suffix == ".py":
        # Only import-probe DOLFINx when asked to run core-only; never skip silently otherwise.
        if _core_only() and not _dolfinx_importable():
            return True
    return None


def pytest_collection_modifyitems(config, items):
    for item in items:
        name = Path(str(item.fspath)).name
        if name.startswith(_DOLFINX_PREFIX):
            item.add_marker(pytest.mark.dolfinx)
        else:
            item.add_marker(pytest.mark.core)


def pytest_report_header(config):
    if _core_only():
        return f"CORE_ONLY=1: DOLFINx importable: {_dolfinx_importable()}"
    return None


@pytest.fixture
def fresh_backend_count(monkeypatch):
    """A process whose 'auto' problems have done no work yet (``core_se3.backend``'s count),
    as in a new ``core-se3`` process: in-process runs compared bit for bit with a child's."""
    from core_se3 import backend
    monkeypatch.setattr(backend._Rent, "saved", 0.0)
    monkeypatch.setattr(backend._Rent, "switched", False)
    monkeypatch.setattr(backend._Rent, "cold", False)          # a warm kernel cache
    return backend._Rent


@pytest.fixture
def pinned_backend(monkeypatch):
    """One backend for every run of a test, in this process and its children
    (``CORE_SE3_BACKEND``): runs compared bit for bit then take the same path whatever the
    'auto' rule's count (tests/test_backend.py covers the count itself)."""
    from core_se3.backend import pin_for_timing
    name = pin_for_timing(dict(os.environ))          # the same choice the timing studies make
    monkeypatch.setenv("CORE_SE3_BACKEND", name)
    return name


_THROTTLED_CLI = """
import sys, time
from core_se3.io import checkpoint
save = checkpoint.Checkpoint.save
def slow_save(self, *a, **k):
    out = save(self, *a, **k)
    time.sleep(%r)
    return out
checkpoint.Checkpoint.save = slow_save
from core_se3.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.fixture
def throttled_cli():
    """``throttled_cli(args, pause=0.3)``: the command line of a real ``core-se3 ARGS`` process
    that pauses ``pause`` seconds after each checkpoint it writes, so that a test's signal lands
    mid-run however busy the machine is (unthrottled, a small run can finish all its steps
    between two of the test's polls -- CI saw exactly that once).  The run itself is unchanged."""
    def command(args, pause=0.3):
        return [sys.executable, "-c", _THROTTLED_CLI % float(pause), *args]
    return command


_SESSION_TMP = []


def pytest_sessionstart(session):
    """``tempfile.mkdtemp()`` and friends (about 25 docstring examples use them) make their
    files in one directory of this test session, removed at its end, instead of leaving them
    in /tmp (this process only: child processes keep their own TMPDIR)."""
    # pytest's own tmp_path root stays where it was (kept for failed tests, pruned by pytest)
    os.environ.setdefault("PYTEST_DEBUG_TEMPROOT", tempfile.gettempdir())
    _SESSION_TMP.append((tempfile.tempdir, tempfile.mkdtemp(prefix="core-se3-tests-")))
    tempfile.tempdir = _SESSION_TMP[-1][1]


def pytest_sessionfinish(session, exitstatus):
    import shutil
    if _SESSION_TMP:
        old, path = _SESSION_TMP.pop()
        tempfile.tempdir = old
        shutil.rmtree(path, ignore_errors=True)
