"""A plot drawn beside the computation: a forked process imports matplotlib while the caller
solves, then draws the one plot it is sent.

Importing matplotlib and its Agg canvas takes about half a second, as long as the whole solve of
a small catalogue case; on a machine with two cores the two now overlap.  The job is sent by
pickle (the function and its arguments) once the results exist; an exception of the plot is
sent back and raised in the caller, with its type.  Where ``os.fork`` is missing, under MPI
(forking an MPI process is unsafe), or when the job cannot be pickled, the plot is drawn in
the caller as before.
"""
from __future__ import annotations

import os
import pickle
import traceback

__all__ = ["PlotProcess"]

_ERROR_LIMIT = 60_000            # bytes of the pickled exception (below a pipe's 64 kB buffer)


def _child(job_r, err_w):
    """The worker: import matplotlib, read one job until EOF, draw it; never returns."""
    code = 0
    try:
        from .plots import new_figure
        new_figure((1.0, 1.0))                    # matplotlib, its figure and the Agg canvas
        with os.fdopen(job_r, "rb") as fh:
            data = fh.read()
        if data:
            fn, args, kw = pickle.loads(data)
            fn(*args, **kw)
    except BaseException as exc:                  # noqa: BLE001 (sent to the caller, raised there)
        code = 1
        try:
            blob = pickle.dumps(exc)
        except Exception:                         # an exception that does not pickle: its text
            blob = b""
        if not blob or len(blob) > _ERROR_LIMIT:
            blob = pickle.dumps(RuntimeError(traceback.format_exc()[-4000:]))
        os.write(err_w, blob)
    os._exit(code)


class PlotProcess:
    """Draw one plot in a forked worker that has imported matplotlib in the meantime.

    Use as a context manager around the computation; :meth:`draw` sends the job and waits for
    the PNG (:meth:`submit` and :meth:`wait` split the two, so that the caller writes its other
    output while the worker draws); leaving the block without a job lets the worker exit unused.

    Parameters
    ----------
    enabled : bool, optional
        False: no worker, :meth:`draw` draws in the caller (as it also does without ``os.fork``).

    Example
    -------
    >>> import os, tempfile
    >>> from core_se3.io.plots import plot_load_deflection
    >>> path = os.path.join(tempfile.mkdtemp(), "curve.png")
    >>> with PlotProcess() as plots:                 # matplotlib is imported beside this block
    ...     loads, u = [0.0, 1.0], {"uz": [0.0, 0.5]}  # ... the solve ...
    ...     _ = plots.draw(plot_load_deflection, path, loads, u)
    >>> os.path.getsize(path) > 0
    True
    """

    def __init__(self, enabled=True):
        self.pid = None
        self._job = self._err = None
        self._pending = None                      # a job run by wait() (no worker)
        if not (enabled and hasattr(os, "fork")):
            return
        job_r, job_w = os.pipe()
        err_r, err_w = os.pipe()
        try:
            pid = os.fork()
        except OSError:
            for fd in (job_r, job_w, err_r, err_w):
                os.close(fd)
            return
        if pid == 0:
            os.close(job_w)
            os.close(err_r)
            _child(job_r, err_w)
        os.close(job_r)
        os.close(err_w)
        self.pid, self._job, self._err = pid, job_w, err_r

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def draw(self, fn, *args, **kw):
        """``fn(*args, **kw)``, drawn by the worker (in the caller without one); waits for it.
        Returns fn's value when drawn here, None when drawn by the worker; an exception of the
        plot is raised here either way."""
        self.submit(fn, *args, **kw)
        return self.wait()

    def submit(self, fn, *args, **kw):
        """Send ``fn(*args, **kw)`` to the worker and return at once, so that the caller writes
        its other output while the worker draws; :meth:`wait` collects it.  Without a worker, or
        when the job does not pickle, the job is kept and run by :meth:`wait` (the caller's
        other output is then written first, as it is with a worker)."""
        if self.pid is not None:
            try:
                payload = pickle.dumps((fn, args, kw))
            except Exception:                     # not picklable: drawn here, by wait()
                self.close()
            else:
                try:
                    with os.fdopen(self._job, "wb") as fh:
                        fh.write(payload)
                except BrokenPipeError:           # the worker stopped before the job: its error
                    pass
                self._job = None
                return
        self._pending = (fn, args, kw)

    def wait(self):
        """Finish the submitted plot: wait for the worker and raise its exception here, or run
        a job kept by :meth:`submit` and return its value (None without a job)."""
        if self._pending is not None:
            (fn, args, kw), self._pending = self._pending, None
            return fn(*args, **kw)
        if self.pid is not None and self._job is None:
            self._wait()
        return None

    def _wait(self):
        _, status = os.waitpid(self.pid, 0)
        self.pid = None
        with os.fdopen(self._err, "rb") as fh:
            blob = fh.read()
        self._err = None
        if os.waitstatus_to_exitcode(status) != 0:
            exc = pickle.loads(blob) if blob else RuntimeError(f"the plot process ended with status {status}")
            raise exc

    def close(self):
        """Let an unused worker exit (EOF on its job pipe) and reap it."""
        if self.pid is None:
            return
        if self._job is not None:
            os.close(self._job)
            self._job = None
        try:
            self._wait()
        except BaseException:                     # noqa: BLE001 (an unused worker's import error)
            pass
