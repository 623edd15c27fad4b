"""A one-line progress bar for terminals: step, load factor (or arc length), Newton iterations,
residual, elapsed time and an estimate of the time left; silent when not enabled.

Enabled (by the front ends) only on a terminal and not with ``--quiet``; it starts drawing
after ``delay`` seconds, so short runs print nothing.

Example
-------
>>> import io
>>> out = io.StringIO()
>>> bar = Progress(4, enabled=True, stream=out, delay=0.0)
>>> bar.update(2, lam=0.5, iterations=3, residual=1e-12)
>>> "step 2/4" in out.getvalue() and "left" in out.getvalue()
True
"""
from __future__ import annotations

import logging
import re
import sys
import time

__all__ = ["Progress", "LogProgress"]


class Progress:
    """Progress of ``total`` steps (None: unknown; then ``fraction`` drives the estimate).

    Parameters
    ----------
    total : int or None
        Number of steps (None for arc length, whose end is a load factor).
    enabled : bool
        Draw at all (the front ends: on a terminal and not ``--quiet``).
    stream : file-like, optional
        Where to draw (default stdout).
    width : int, optional
        Width of the bar in characters.
    delay : float, optional
        Seconds before the first drawing [s].

    Example
    -------
    >>> import io
    >>> out = io.StringIO()
    >>> Progress(4, enabled=False, stream=out).update(1, 0.25, 3, 1e-12); out.getvalue()
    ''
    >>> bar = Progress(None, enabled=True, stream=out, delay=0.0)
    >>> bar.update(3, lam=0.5, iterations=4, residual=1e-9, fraction=0.5); bar.close("done")
    >>> "step 3  lam 0.5" in out.getvalue(), out.getvalue().splitlines()[-1]
    (True, 'done')
    """

    def __init__(self, total, enabled, stream=None, width=24, delay=2.0):
        self.total, self.enabled, self.width, self.delay = total, bool(enabled), width, delay
        self.stream = stream or sys.stdout
        self.t0 = time.perf_counter()
        self.drawn = False

    def update(self, k, lam, iterations, residual, fraction=None, extra="", label=None):
        """Redraw after step k at load factor lam; ``fraction`` of the path done (default
        k / total); ``label`` replaces "step k/total  lam ..." (e.g. "run 2/5" of a sweep)."""
        if not self.enabled:
            return
        elapsed = time.perf_counter() - self.t0
        if elapsed < self.delay and not self.drawn:
            return
        frac = fraction if fraction is not None else (k / self.total if self.total else None)
        n = int(round(self.width * min(max(frac or 0.0, 0.0), 1.0)))
        bar = "#" * n + "." * (self.width - n)
        left = ""
        if frac and 0 < frac < 1:
            left = f"  ~{elapsed * (1 - frac) / frac:.0f} s left"
        total = f"/{self.total}" if self.total else ""
        head = label or f"step {k}{total}  lam {lam:.4g}  it {iterations:>2d}  res {residual:.1e}"
        self.stream.write(f"\r[{bar}] {head}{extra}  {elapsed:.1f} s{left} ")
        self.stream.flush()
        self.drawn = True

    def close(self, message=""):
        """End the line (and print ``message``)."""
        if self.enabled and (self.drawn or message):
            self.stream.write(("\n" if self.drawn else "") + (message + "\n" if message else ""))
            self.stream.flush()


class LogProgress(logging.Handler):
    """Drive a :class:`Progress` from the solvers' per-step log (logger ``core_se3``): every
    converged step's ``lam`` (and ``in N it``) redraws the bar, the fraction being lam / lam_end
    (for runs whose steps are not known in advance, e.g. ``core-se3 bench run``).

    Parameters
    ----------
    bar : Progress
        The bar to redraw.
    lam_end : float, optional
        Final load factor (the end of the bar).

    Example
    -------
    >>> import io, logging
    >>> out = io.StringIO()
    >>> h = LogProgress(Progress(None, enabled=True, stream=out, delay=0.0))
    >>> h.emit(logging.makeLogRecord({"msg": "  lam %.6g: %s in %d it", "args": (0.5, "ok", 3)}))
    >>> "step 1  lam 0.5" in out.getvalue()
    True
    """

    _LAM = re.compile(r"\blam ([-+0-9.eE]+)")
    _IT = re.compile(r"in (\d+) it|\bit (\d+)")

    def __init__(self, bar, lam_end=1.0):
        super().__init__(level=logging.INFO)
        self.bar, self.lam_end, self.k = bar, float(lam_end), 0

    def emit(self, record):
        try:
            text = record.getMessage()
        except Exception:          # pragma: no cover - a malformed record
            return
        m = self._LAM.search(text)
        if m is None or "FAIL" in text or "REJECTED" in text:
            return
        self.k += 1
        it = self._IT.search(text)
        its = int(next(g for g in it.groups() if g)) if it else 0
        lam = float(m.group(1).rstrip("."))
        self.bar.update(self.k, lam, its, 0.0, fraction=min(abs(lam / self.lam_end), 1.0) if self.lam_end else None)

    def __enter__(self):
        logger = logging.getLogger("core_se3")
        self.old_level = logger.level
        if logger.getEffectiveLevel() > logging.INFO:
            logger.setLevel(logging.INFO)
        logger.addHandler(self)
        return self

    def __exit__(self, *exc):
        logger = logging.getLogger("core_se3")
        logger.removeHandler(self)
        logger.setLevel(self.old_level)
        self.bar.close()
        return False
