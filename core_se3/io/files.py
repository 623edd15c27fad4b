"""Atomic file writes (:func:`atomic_path`, from ``results.atomic``, whose ``write_json`` uses it
too): every file is written to a temporary name in its own directory and moved into place with
os.replace, which is atomic on POSIX: a reader (or a run killed at any instant)
sees either the previous complete file or the new complete file, never a partial one.

Example
-------
>>> import os, tempfile
>>> d = tempfile.mkdtemp()
>>> p = write_text_atomic(os.path.join(d, "a.txt"), "done")
>>> open(p).read(), sorted(os.listdir(d))
('done', ['a.txt'])
"""
from __future__ import annotations

import os

from ..results.atomic import atomic_path
from ..results.document import write_json

__all__ = ["atomic_path", "write_text_atomic", "write_json_atomic", "check_input_file", "read_input_file",
           "without_contents"]


def write_text_atomic(path, text):
    """Write ``text`` to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or path-like
        The file.
    text : str
        Its new content.

    Returns
    -------
    str
        The path.

    Example
    -------
    >>> import os, tempfile
    >>> p = write_text_atomic(os.path.join(tempfile.mkdtemp(), "sub", "b.txt"), "done")
    >>> open(p).read()
    'done'
    """
    with atomic_path(path) as tmp:
        with open(tmp, "w") as fh:
            fh.write(text)
    return os.fspath(path)


def write_json_atomic(path, doc):
    """``doc`` (anything ``json.dumps`` accepts) written atomically as strict JSON, indent 1 (a
    NaN or infinite number as null, named under ``non_finite``): ``results.write_json``, which
    is atomic itself; kept under this name for the run directories.  Returns the path.

    Example
    -------
    >>> import json, os, tempfile
    >>> p = write_json_atomic(os.path.join(tempfile.mkdtemp(), "r.json"), {"status": "running", "step": 3})
    >>> json.load(open(p))
    {'status': 'running', 'step': 3}
    """
    return write_json(path, doc)


def check_input_file(path, limit, what="an input file"):
    """None if ``path`` is a regular file of 1 to ``limit`` bytes, else the reason it is not
    read (a device such as /dev/zero, a pipe, a directory, a missing, empty or oversized file):
    input files are read only when they are regular and bounded.

    Example
    -------
    >>> check_input_file("/dev/zero", 1 << 20)
    "'/dev/zero' is not a regular file (a device, a pipe or a directory): give an input file"
    """
    import stat
    try:
        st = os.stat(path)
    except OSError as exc:
        return f"cannot read {path!r}: {exc.strerror or exc}"
    if not stat.S_ISREG(st.st_mode):
        return f"{path!r} is not a regular file (a device, a pipe or a directory): give an input file"
    if st.st_size > limit:
        return (f"{path!r} has {st.st_size / 2 ** 20:.1f} MiB, more than the {limit / 2 ** 20:.0f} MiB {what} may "
                "have: is it the right file?")
    if st.st_size == 0:                 # (an empty mesh file failed in meshio with a bare NumPy error)
        return f"{path!r} is empty (0 bytes): is it the right file, and was it saved?"
    return None


def read_input_file(path, limit, what="an input file"):
    """The bytes of a regular input file of at most ``limit`` bytes (read at most limit + 1
    bytes, in case it grows); ValueError with the reason otherwise (:func:`check_input_file`).

    Example
    -------
    >>> import tempfile
    >>> p = write_text_atomic(os.path.join(tempfile.mkdtemp(), "s.toml"), "name = 'x'")
    >>> read_input_file(p, 100)
    b"name = 'x'"
    """
    why = check_input_file(path, limit, what)
    if why is not None:
        raise ValueError(why)
    with open(path, "rb") as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise ValueError(f"{path!r} has more than the {limit / 2 ** 20:.0f} MiB {what} may have")
    return data


def without_contents(message, path, head_bytes=1 << 16):
    """An error message about the file ``path`` without any text of that file: a quoted passage
    whose text occurs anywhere in the file (readers quote the line they failed on, a group's
    name), or any quoted passage when the file cannot be read, becomes '...', and so does what
    follows 'found'; if any 8 characters of what is left (the path aside) still occur in the
    file's first 64 KiB, the detail goes entirely.  A quoted passage that is not in the file --
    the reader's own advice, such as ``triangles = "split"`` -- stays.  An error message must
    never show a file's contents (a scenario may name any file as its mesh).

    Example
    -------
    >>> import tempfile
    >>> p = write_text_atomic(os.path.join(tempfile.mkdtemp(), "m.msh"), "SECRET TOKEN 42\\n")
    >>> without_contents("ReadError: Unexpected line 'SECRET TOKEN 42'", p)
    'ReadError: Unexpected line ...'
    >>> without_contents('it has triangles: set triangles = "split"', p)
    'it has triangles: set triangles = "split"'
    """
    import re
    msg = re.sub(r"(['\"]).*?\1", lambda m: m.group(0) if _absent(m.group(0)[1:-1], path) else "...",
                 str(message))
    msg = re.sub(r"\bfound\b.*", "found ...", msg)
    try:
        with open(path, "rb") as fh:
            head = fh.read(head_bytes).decode("latin-1")
    except OSError:
        return msg
    rest = msg.replace(os.fspath(path), "").replace(os.path.basename(os.fspath(path)), "")
    if any(rest[i:i + 8] in head for i in range(max(len(rest) - 7, 0)) if rest[i:i + 8].strip()):
        return "its contents are not a mesh this reader knows"
    return msg


def _absent(text, path):
    """True if ``text`` (not blank) is certainly not in the file ``path``: searched whole, in
    chunks, ignoring ASCII case (a reader may quote a name in another case), as UTF-8 and
    Latin-1; False if it is there, or the file cannot be read."""
    if not text.strip():
        return False
    needles = {text.lower().encode(enc, "replace") for enc in ("utf-8", "latin-1")}
    keep = max(map(len, needles)) - 1
    try:
        with open(path, "rb") as fh:
            tail = b""
            while True:
                chunk = fh.read(1 << 24)
                if not chunk:
                    return True
                buf = tail + chunk.lower()
                if any(x in buf for x in needles):
                    return False
                tail = buf[len(buf) - keep:] if keep else b""
    except OSError:
        return False
