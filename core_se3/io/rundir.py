"""The output directory of a run: it holds only the run's own files, listed in its manifest, and one
live run at a time.

* **Manifest** (``.core-se3-manifest.json``): every file a run writes is listed there *before*
  it is created (:meth:`RunDirectory.file`), so that whatever a killed run left is known to be
  its own; ``--force`` deletes only the files of a previous run that its manifest lists (and
  their half-written temporaries, and the folders they leave empty: a design run again with
  fewer poses kept an empty ``vtu/<old pose>``), never a file this tool did not write.
* **Another kind's files** (a run's directory given to a sweep, ...): refused, with ``resume``
  and ``force`` too (neither continued nor deleted).
* **Foreign files**: a new run in a directory holding files that no manifest lists is refused
  (naming them) unless ``force``; even then they are kept, and a run refuses to overwrite one of
  them (a resumed run keeps those added beside it).
* **Lock** (``.core-se3.lock``): an exclusive ``flock`` held while the run lives, released by
  the kernel when its process ends however it ends (so a killed run leaves no stale lock); a
  second run on the same directory is refused, naming the first one's process.  A run that
  ends (complete, failed, interrupted, or refusing the directory) deletes the lock file, still
  holding it, so the file is there only while a run lives; a killed run's file stays, unlocked,
  and the next run takes it.

Example
-------
>>> import os, tempfile
>>> d = tempfile.mkdtemp()
>>> with RunDirectory(d, "run").claim() as rd:
...     _ = open(rd.file("results.json"), "w").write("{}")
>>> try:
...     RunDirectory(d, "run").claim()
... except RunDirectoryError as exc:
...     print(str(exc)[len(d):])
 holds the files of an earlier run (results.json): continue it with --resume, start over with --force, or choose another --out directory
>>> open(os.path.join(d, "notes.txt"), "w").close()        # the user's file
>>> with RunDirectory(d, "run").claim(force=True) as rd:   # the old run's files go, notes.txt stays
...     sorted(f for f in os.listdir(d) if not f.startswith("."))
['notes.txt']
"""
from __future__ import annotations

import errno
import fnmatch
import json
import os
import re
import time

from ..errors import CheckpointError, ScenarioWarning
from .files import write_json_atomic

__all__ = ["RunDirectory", "RunDirectoryError", "safe_name", "MANIFEST", "LOCK"]

MANIFEST = ".core-se3-manifest.json"
LOCK = ".core-se3.lock"
#: the kinds of directory whose command continues an earlier one (core-se3 run and sweep --resume)
RESUMABLE = ("run", "sweep")
_TMP = re.compile(r"^\.(?P<name>.+)\.[a-z0-9_]{8}\.tmp")    # io.files.atomic_path's temporaries


class RunDirectoryError(CheckpointError):
    """An output directory that holds another run, files this tool did not write, or a live
    run (its lock); the message says which and what to do.

    Example
    -------
    >>> issubclass(RunDirectoryError, CheckpointError)
    True
    """


def safe_name(name, default="scenario"):
    """A name usable as one directory component under ``out/``: characters other than letters,
    digits, '.', '_' and '-' become '_', and leading dots go (so ``../..`` or ``/etc`` stays under
    ``out/``).

    Example
    -------
    >>> safe_name("../.."), safe_name("/etc/passwd"), safe_name("gripper v2"), safe_name("")
    ('__', '_etc_passwd', 'gripper_v2', 'scenario')
    """
    s = re.sub(r"[^A-Za-z0-9._-]", "_", str(name)).lstrip(".")
    s = s.replace("..", "_")
    return s[:120] or default


class RunDirectory:
    """The output directory ``path`` of one run of ``kind`` ('run', 'sweep', 'design').

    :meth:`claim` takes the lock and checks the contents; :meth:`file` registers a file
    (relative path) and returns its path; :meth:`release` (or the ``with`` block) drops the lock.
    ``previous`` lists the files of an earlier run that the manifest names and that exist.

    Parameters
    ----------
    path : str or path-like
        The directory (created if missing).
    kind : str
        What writes it (in the manifest and the messages).
    patterns : sequence of str, optional
        The relative names a run of this kind writes (fnmatch patterns, e.g. ``vtu/step_*.vtu``):
        a foreign file of such a name is never overwritten, even with force.
    option : str, optional
        The command-line option that names the directory (in the messages; default ``--out``).

    Example
    -------
    See the module docstring.

    >>> RunDirectory("out/x", "run").manifest_path.endswith(MANIFEST)
    True
    """

    def __init__(self, path, kind="run", patterns=(), option="--out"):
        self.path = os.fspath(path)
        self.option = option
        self.kind = kind
        self.patterns = tuple(patterns)
        self.manifest_path = os.path.join(self.path, MANIFEST)
        self.files = []
        self.previous = []
        self.existed = False            # a manifest was there: the directory of an earlier run
        self._lock = None
        self._manifest_kind = None      # what wrote the files the manifest lists ('run', 'sweep', ...)

    # ------------------------------------------------------------------ claiming -------------
    def claim(self, resume=False, force=False, adopt=(), replace=False):
        """Lock the directory and check what it holds.

        Parameters
        ----------
        resume : bool
            Continue the run whose files the manifest lists (they stay); a directory that does
            not exist is a RunDirectoryError (nothing to continue; it is not created).
        force : bool
            Start over: delete the files a previous run of this tool listed, write beside foreign
            files (never over them).
        adopt : sequence of str
            Patterns of files of an older version's run (no manifest) that ``resume`` takes as
            its own.
        replace : bool
            Start over without ``force`` where the directory holds only this tool's files (a
            ``bench run --vtu`` directory written again); foreign files are still refused.

        Returns
        -------
        RunDirectory
            self, locked.
        """
        if os.path.exists(self.path) and not os.path.isdir(self.path):
            raise RunDirectoryError(f"{self.option} {self.path!r} is a file, not a directory: nothing was written; "
                                    f"choose a directory (new or of an earlier {self.kind})")
        if resume and not os.path.exists(self.path):      # (it was created, and a sweep started afresh)
            raise RunDirectoryError(f"nothing to resume: {self.option} {self.path!r} does not exist (no earlier "
                                    f"{self.kind} there); give the directory of the {self.kind} to continue, or "
                                    "start one without --resume")
        os.makedirs(self.path, exist_ok=True)
        self._take_lock()
        try:
            listed = self._read_manifest(damaged_ok=resume and bool(adopt))
            self.existed = listed is not None or self._damaged
            present = self._walk()
            if listed is None and resume:       # a run of an older version: its files by name
                listed = [f for f in present if any(fnmatch.fnmatch(f, p) for p in adopt)]
                if not listed:                  # refused before a manifest is left among the user's files
                    raise RunDirectoryError(f"nothing to resume: {self.path} holds no {self.kind} (no file core-se3 "
                                            f"wrote); give the directory of the {self.kind} to continue, or start one "
                                            "without --resume")
            listed = listed or []
            ours = set(listed) | {MANIFEST, LOCK}
            self.previous = [f for f in listed if f in present]
            self._check_kind()
            foreign = [f for f in present if f not in ours and not self._temporary(f, ours)]
            force = force or (replace and not foreign and not resume)
            self._check(foreign, resume, force)
            if force and not resume:
                self._delete(self.previous, ours, present)
                listed, self.previous = [], []
            else:
                self._delete([], ours, present)          # only half-written temporaries
            self.files = [f for f in listed if f in present]
            self._write_manifest()
        except BaseException:
            self.release()                      # deletes the lock file: the directory as it was
            raise
        return self

    def _check_kind(self):
        """A directory of another kind's files (a run's, entered by a sweep): neither continued nor
        deleted -- the messages would call them this kind's, and --force deleted a run's results."""
        other = self._manifest_kind
        if self.previous and other is not None and other != self.kind:
            raise RunDirectoryError(
                f"{self.path} holds the files of a {other} ({_some(self.previous)}), not of a {self.kind}: a "
                f"{self.kind} neither continues (--resume) nor deletes (--force) them; choose another {self.option} directory")

    def _check(self, foreign, resume, force):
        where = self.path
        if foreign and not force and not resume:          # a resumed run keeps files added beside it
            raise RunDirectoryError(
                f"{where} holds files that core-se3 did not write ({_some(foreign)}): choose an empty or new "
                f"{self.option} directory, or --force to write beside them (--force never deletes them)")
        clash = [f for f in foreign if any(fnmatch.fnmatch(f, p) for p in self.patterns)]
        if clash:
            raise RunDirectoryError(
                f"{where} holds files that core-se3 did not write under the names a {self.kind} writes "
                f"({_some(clash)}): --force does not overwrite them; move them away or choose another {self.option}")
        if self.previous and not resume and not force:
            go_on = "continue it with --resume, " if self.kind in RESUMABLE else ""    # (a design starts over)
            raise RunDirectoryError(
                f"{where} holds the files of an earlier {self.kind} ({_some(self.previous)}): {go_on}start over "
                f"with --force, or choose another {self.option} directory")

    def start_over(self):
        """Delete the files of the earlier run (a resume of a run that stopped before it saved
        anything to continue from)."""
        self._delete(self.previous, set(self.files), [])
        self.previous, self.files = [], []
        self._write_manifest()

    # ------------------------------------------------------------------ writing --------------
    def file(self, relative):
        """The path of the run's file ``relative`` (e.g. 'vtu/step_0003.vtu'), listed in the
        manifest (written atomically) before the caller creates it."""
        rel = os.path.normpath(relative)
        if rel.startswith("..") or os.path.isabs(rel):
            raise ValueError(f"{relative!r} is not inside the run directory")
        if rel not in self.files:
            # the last guard of a file this tool did not write: one the claim could not see (in a
            # folder linked in from elsewhere) or put there since
            if os.path.lexists(os.path.join(self.path, rel)):
                raise RunDirectoryError(f"{self.path} holds {rel}, which core-se3 did not write: the {self.kind} "
                                        f"would overwrite it; move it away, or choose another {self.option}")
            self.files.append(rel)
            self._write_manifest()
        return os.path.join(self.path, rel)

    def release(self):
        """Drop the lock and delete its file, still holding it (a process that opened the file
        before and locks it after finds it gone and locks the name's new file: ``_take_lock``), so
        that a lock file is there only while a run lives.  A killed run's file stays, unlocked (the
        kernel drops the lock when the process ends): the next run takes it."""
        if self._lock is not None:
            path = os.path.join(self.path, LOCK)
            if _same_file(self._lock, path):
                try:
                    os.unlink(path)
                except OSError:
                    pass
            os.close(self._lock)
            self._lock = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()
        return False

    # ------------------------------------------------------------------ internals ------------
    def _take_lock(self):
        """flock the lock file.  A process that ends deletes the file, still holding it
        (:meth:`release`): one that opened it before then and locks it after finds its file gone from the
        directory (another inode at the name, or none) and tries again on the name's file."""
        import fcntl
        path = os.path.join(self.path, LOCK)
        for _ in range(100):
            try:
                fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                try:
                    fd = os.open(path, os.O_RDWR)
                except FileNotFoundError:    # deleted by a run ending in between
                    continue
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                os.close(fd)
                if exc.errno not in (errno.EAGAIN, errno.EACCES):
                    raise
                raise RunDirectoryError(f"{self.path} is in use by another live run ({_holder(path)}): wait for it "
                                        f"to end, or choose another {self.option} directory") from None
            if _same_file(fd, path):
                break
            os.close(fd)
        else:
            raise RunDirectoryError(f"{path} keeps being deleted and created: another process is at it; choose "
                                    f"another {self.option} directory")
        os.ftruncate(fd, 0)
        os.write(fd, json.dumps(dict(pid=os.getpid(), kind=self.kind, started=time.strftime(
            "%Y-%m-%d %H:%M:%S"))).encode())
        self._lock = fd

    def _read_manifest(self, damaged_ok=False):
        """The files the manifest lists (None without one); a damaged manifest is an error, or
        with ``damaged_ok`` (a resume, which takes the run's files by name as an older version's:
        it stopped there before, and the run could only start over elsewhere) None and a
        ScenarioWarning saying so."""
        self._manifest_kind, self._damaged = None, False
        if not os.path.exists(self.manifest_path):
            return None
        try:
            with open(self.manifest_path, "rb") as fh:
                doc = json.loads(fh.read(1 << 24))
            files = [os.path.normpath(f) for f in doc["files"]]
            self._manifest_kind = doc.get("kind") if isinstance(doc.get("kind"), str) else None
            if doc.get("tool") != "core-se3" or any(f.startswith("..") or os.path.isabs(f) for f in files):
                raise ValueError("not a core-se3 manifest")
        except (OSError, ValueError, KeyError, TypeError) as exc:
            if damaged_ok:
                import warnings
                self._damaged = True
                warnings.warn(ScenarioWarning(f"{self.manifest_path} is damaged ({type(exc).__name__}): the run's files "
                                              "are taken by their names (results.json, checkpoint.npz, vtu/...) and "
                                              "the manifest written anew"), stacklevel=4)
                return None
            again = "continue it with --resume (its files are then taken by their names), or " \
                if self.kind in ("run", "sweep") else ""
            raise RunDirectoryError(f"{self.manifest_path} is damaged ({type(exc).__name__}): it lists the files "
                                    f"of the run that wrote this directory; {again}choose another {self.option}") from None
        return files

    def _write_manifest(self):
        write_json_atomic(self.manifest_path, dict(tool="core-se3", kind=self.kind, files=sorted(self.files)))

    def _walk(self):
        """Every file under the directory, and those of folders linked in from elsewhere where
        the run writes (a ``vtu`` that is a link to a user's folder: its files were overwritten,
        even with --force), each real folder once (a link to an ancestor does not loop); other
        linked folders are not entered (a link to a large data set beside the run)."""
        out, seen = [], set()
        for root, dirs, files in os.walk(self.path, followlinks=True):
            real = os.path.realpath(root)
            if real in seen:
                dirs[:] = []
                continue
            seen.add(real)
            rel = os.path.relpath(root, self.path)
            dirs[:] = [d for d in dirs if not os.path.islink(os.path.join(root, d))
                       or self._written_in(os.path.normpath(os.path.join(rel, d)))]
            for f in files:
                out.append(os.path.relpath(os.path.join(root, f), self.path))
        return sorted(out)

    def _written_in(self, folder):
        """True if the run writes into ``folder`` (relative) or below it (its ``patterns``)."""
        parts = folder.split(os.sep)
        return any(len(p.split("/")) > len(parts) and all(fnmatch.fnmatch(a, b) for a, b in zip(parts, p.split("/")))
                   for p in self.patterns)

    @staticmethod
    def _temporary(f, ours):
        """A half-written temporary of one of ``ours`` (atomic_path's name in the same folder)."""
        d, base = os.path.split(f)
        m = _TMP.match(base)
        return m is not None and os.path.join(d, m.group("name")) in ours

    def _delete(self, files, ours, present):
        """Delete the listed files and the half-written temporaries of ``ours``, then the folders
        that held them and are left empty (a re-run with fewer poses: an empty ``vtu/<old pose>``
        read as a pose of this run); a folder holding anything else stays."""
        gone = list(files) + [p for p in present if p not in ours and self._temporary(p, ours)]
        for f in gone:
            try:
                os.unlink(os.path.join(self.path, f))
            except FileNotFoundError:
                pass
        folders = {os.path.dirname(f) for f in gone}
        for d in sorted({os.path.join(*p.split(os.sep)[:k]) for p in folders if p
                         for k in range(1, len(p.split(os.sep)) + 1)}, key=len, reverse=True):
            try:
                os.rmdir(os.path.join(self.path, d))             # only when empty
            except OSError:
                pass


def _same_file(fd, path):
    """The open file ``fd`` is the one at ``path`` now."""
    try:
        a, b = os.fstat(fd), os.stat(path)
    except FileNotFoundError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _some(names, k=5):
    return ", ".join(names[:k]) + (f" and {len(names) - k} more" if len(names) > k else "")


def _holder(path):
    try:
        with open(path) as fh:
            info = json.loads(fh.read(4096) or "{}")
        return f"a {info.get('kind', 'run')} of process {info.get('pid', '?')}, started {info.get('started', '?')}"
    except (OSError, ValueError):
        return "another process"
