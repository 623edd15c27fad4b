"""What the commands of ``core-se3`` share: the exit status and the one error line of a failure,
the progress switch."""
from __future__ import annotations

import sys

from ..backend import launched_rank
from ..errors import ConvergenceError

__all__ = ["error_code", "output_error", "progress_on", "interrupted", "whole_number"]


def error_code(exc):
    """Print a core_se3 error; the exit status: 3 for a solver that did not converge (the
    converged steps are kept), 2 for bad input.

    Example
    -------
    >>> from core_se3.errors import ScenarioError
    >>> error_code(ScenarioError("bad", "s.toml", "mesh"))
    2
    """
    if launched_rank() == 0:             # under mpirun every rank meets the same error
        print(f"error: {exc}", file=sys.stderr)
    return 3 if isinstance(exc, ConvergenceError) else 2


def output_error(exc, kept):
    """An output that could not be written (an unwritable path or a full disk): one error line,
    exit status 2."""
    if launched_rank() == 0:
        print(f"error: cannot write the outputs ({exc}): choose a writable path; {kept}", file=sys.stderr)
    return 2


def interrupted(exc, what):
    """A run ended by SIGTERM or Ctrl-C (``io.lifecycle.Terminated``): one line, exit status
    143 (SIGTERM) or 130 (SIGINT), as a shell reports a process killed by them.

    Example
    -------
    >>> from core_se3.io.lifecycle import Terminated
    >>> interrupted(Terminated("SIGTERM"), "the checkpoint keeps the last step")
    143
    """
    name = getattr(exc, "signal_name", "SIGINT")
    if launched_rank() == 0:
        print(f"\ninterrupted ({name}): {what}", file=sys.stderr)
    return 143 if name == "SIGTERM" else 130


def progress_on(args):
    """Progress line: with --progress, else on a terminal unless --quiet."""
    if getattr(args, "progress", False):
        return True
    return not getattr(args, "quiet", False) and sys.stdout.isatty()


def whole_number(what):
    """An argparse type: a whole number >= 1 (``what`` names it in the error).

    Example
    -------
    >>> whole_number("steps")("3")
    3
    """
    import argparse

    def parse(s):
        try:
            n = int(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be a whole number, got {s!r}") from None
        if n < 1:
            raise argparse.ArgumentTypeError(f"{what} must be at least 1, got {n}")
        return n
    return parse


def existing_json(path):
    """(exists, value) of the file ``path``: False, None where there is none; True, None where it
    is not readable JSON; else True and the parsed value (what --json may overwrite is decided
    from it: ``bench run``'s and ``check-mesh``'s own earlier outputs only)."""
    import json
    import os
    if not os.path.exists(path):
        return False, None
    try:
        with open(path) as fh:
            return True, json.load(fh)
    except (OSError, ValueError):
        return True, None
