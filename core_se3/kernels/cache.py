"""Where numba keeps the compiled kernels: one cache directory per version of their source.

numba's own cache checks only the file that defines a function (its modification time and
size).  The kernels inline functions of other files at numba's IR level (``element_ops``,
``csr``, ``lie``), so after an edit -- or an upgrade of core_se3 that leaves one of the kernel
files as it was -- a cached driver kept running the old code of the functions it had inlined
(seen while changing ``element_ops``: the drivers of ``element_passes`` ran the old material
block until the cache was deleted).  A wrong answer from a stale cache must not be possible, so
the kernels are cached under a directory named by a fingerprint of *all* their source files:
any change of any kernel file starts a new, empty cache.

The directory is ``<base>/core_se3-kernels-<fingerprint>``, with ``base`` numba's
``NUMBA_CACHE_DIR`` when set, else the kernels' own ``__pycache__`` when it is writable, else
``$XDG_CACHE_HOME/core_se3`` (``~/.cache/core_se3``).  The setting applies only while the
kernel modules are imported (their functions are decorated then), so other numba code in the
same process keeps numba's usual cache.  Fingerprint directories of earlier sources under the
kernels' ``__pycache__`` are removed (they can never be used again).
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
from pathlib import Path

__all__ = ["source_fingerprint", "cache_directory", "fingerprinted_cache"]

HERE = Path(__file__).resolve().parent
PREFIX = "core_se3-kernels-"


def source_fingerprint(paths=None):
    """A short hash (16 hex digits) of the kernels' source files (names and contents).

    Parameters
    ----------
    paths : iterable of path-like, optional
        The files to hash; default every ``*.py`` file of ``core_se3/kernels``.

    Example
    -------
    >>> import os, tempfile
    >>> d = tempfile.mkdtemp(); p = os.path.join(d, "k.py")
    >>> _ = open(p, "w").write("x = 1\\n"); a = source_fingerprint([p])
    >>> _ = open(p, "w").write("x = 2\\n"); len(a), a == source_fingerprint([p])
    (16, False)
    """
    h = hashlib.sha1()
    for p in sorted(Path(q) for q in (paths if paths is not None else HERE.glob("*.py"))):
        h.update(p.name.encode())
        h.update(b"\0")
        h.update(p.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


def _writable(d):
    try:
        os.makedirs(d, exist_ok=True)
        with open(os.path.join(d, f".probe-{os.getpid()}"), "w"):
            pass
        os.remove(os.path.join(d, f".probe-{os.getpid()}"))
        return True
    except OSError:
        return False


def cache_directory(fingerprint=None, base=None):
    """The numba cache directory of the kernels' current source (module docstring).

    Parameters
    ----------
    fingerprint : str, optional
        Default :func:`source_fingerprint` of the kernels.
    base : path-like, optional
        Default ``NUMBA_CACHE_DIR``, else the kernels' ``__pycache__`` if writable, else the
        user's cache directory.

    Example
    -------
    >>> import tempfile
    >>> d = cache_directory("0123456789abcdef", base=tempfile.mkdtemp())
    >>> os.path.basename(d)
    'core_se3-kernels-0123456789abcdef'
    """
    fp = fingerprint or source_fingerprint()
    if base is None:
        base = os.environ.get("NUMBA_CACHE_DIR") or None
    if base is None:
        tree = HERE / "__pycache__"
        if _writable(tree):
            base = tree
        else:
            xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
            base = os.path.join(xdg, "core_se3")
    return os.path.join(os.fspath(base), PREFIX + fp)


def _prune(current):
    """Remove what can never be loaded again from the kernels' __pycache__: the fingerprint
    directories of earlier sources, and the index and data files of numba's own layout (the
    kernels' caches before this module)."""
    tree = HERE / "__pycache__"
    if Path(current).parent != tree or not tree.is_dir():
        return
    for d in tree.glob(PREFIX + "*"):
        if d.is_dir() and os.fspath(d) != os.fspath(current):
            shutil.rmtree(d, ignore_errors=True)
    for f in [*tree.glob("*.nbi"), *tree.glob("*.nbc")]:
        with contextlib.suppress(OSError):
            f.unlink()


@contextlib.contextmanager
def fingerprinted_cache():
    """Within this context, numba functions decorated with ``cache=True`` are cached in
    :func:`cache_directory` (numba's ``config.CACHE_DIR`` is set, then restored)."""
    from numba.core import config
    path = cache_directory()
    _prune(path)
    previous = config.CACHE_DIR
    config.CACHE_DIR = path
    try:
        yield path
    finally:
        config.CACHE_DIR = previous
