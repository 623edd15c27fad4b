"""How a run ends when it is asked to: SIGTERM (what a cluster's scheduler sends at a time limit,
``kill PID``) and SIGINT (Ctrl-C) both become a :class:`Terminated` exception in the main thread,
so that a run writes ``status = "interrupted"``, says so and keeps a resumable checkpoint in
either case (Python alone turns only SIGINT into KeyboardInterrupt; SIGTERM kills the process at
once).  While a run writes its last files, :func:`held_signals` defers further signals until the
files are complete.

Example
-------
>>> import os, signal
>>> with termination_as_interrupt():
...     try:
...         os.kill(os.getpid(), signal.SIGTERM)
...     except Terminated as exc:
...         print(exc.signal_name, isinstance(exc, KeyboardInterrupt))
SIGTERM True
"""
from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["Terminated", "termination_as_interrupt", "held_signals", "SIGNALS"]

SIGNALS = (signal.SIGTERM, signal.SIGINT)


class Terminated(KeyboardInterrupt):
    """A run ended by a signal: ``signal_name`` 'SIGTERM' or 'SIGINT' (a KeyboardInterrupt, so
    that code catching Ctrl-C handles both).

    Example
    -------
    >>> Terminated("SIGTERM").signal_name
    'SIGTERM'
    """

    def __init__(self, signal_name="SIGINT"):
        super().__init__(signal_name)
        self.signal_name = signal_name

    def describe(self):
        """'SIGTERM (a kill or a scheduler's time limit)' or 'Ctrl-C (SIGINT)', for messages."""
        return "SIGTERM (a kill or a scheduler's time limit)" if self.signal_name == "SIGTERM" else "Ctrl-C (SIGINT)"


def _raise(signum, frame):
    raise Terminated(signal.Signals(signum).name)


@contextlib.contextmanager
def termination_as_interrupt():
    """Within this context (in the main thread; elsewhere a no-op), SIGTERM and SIGINT raise
    :class:`Terminated`; the previous handlers come back afterwards."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.signal(s, _raise) for s in SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


@contextlib.contextmanager
def held_signals():
    """Within this context, SIGTERM and SIGINT are remembered instead of acted on; the first one
    that came is raised as :class:`Terminated` when the context ends (so that the files written
    in it are complete).  A no-op outside the main thread.

    Example
    -------
    >>> import os, signal
    >>> with termination_as_interrupt():
    ...     try:
    ...         with held_signals():
    ...             os.kill(os.getpid(), signal.SIGINT)
    ...             print("still writing")
    ...     except Terminated as exc:
    ...         print("then", exc.signal_name)
    still writing
    then SIGINT
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending = []
    old = {s: signal.signal(s, lambda signum, frame: pending.append(signum)) for s in SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
    if pending:
        raise Terminated(signal.Signals(pending[0]).name)
