"""The one atomic writer of the package: a file is written under a temporary name in its own
directory and moved into place with os.replace, atomic on POSIX, so a reader (or a run killed at
any instant, or a write that fails half way) sees the previous complete file or the new complete
file, never a partial one.  Used by ``results.write_json``, ``io.files`` (text, JSON, checkpoints)
and ``io.plots`` (every PNG, ``core-se3 bench run --plot`` too).
"""
from __future__ import annotations

import contextlib
import os
import tempfile

__all__ = ["atomic_path"]


@contextlib.contextmanager
def atomic_path(path, suffix=None):
    """Yield a temporary path next to ``path`` (same extension); on success move it to ``path``.

    If the block raises, the temporary file is removed and ``path`` keeps its previous content.
    The file is fsync'ed before the move; its permissions follow the umask (not mkstemp's 0600).

    Parameters
    ----------
    path : str or path-like
        The final file (its directory is created if needed).
    suffix : str, optional
        Extension of the temporary file (default that of ``path``: writers that choose the format
        by extension, e.g. meshio, still work).

    Yields
    ------
    str
        The temporary path to write.

    Example
    -------
    >>> import os, pathlib, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "a.txt")
    >>> with atomic_path(p) as tmp:
    ...     _ = pathlib.Path(tmp).write_text("complete")
    >>> try:
    ...     with atomic_path(p) as tmp:
    ...         _ = pathlib.Path(tmp).write_text("partial")
    ...         raise KeyboardInterrupt                     # a run killed while writing
    ... except KeyboardInterrupt:
    ...     pass
    >>> open(p).read(), os.listdir(os.path.dirname(p))
    ('complete', ['a.txt'])
    """
    path = os.fspath(path)
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    ext = suffix if suffix is not None else os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp" + ext, dir=d)
    os.close(fd)
    os.chmod(tmp, 0o666 & ~_umask())          # mkstemp makes 0600; give the usual permissions
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _umask():
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
