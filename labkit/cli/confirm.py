"""A confirmation above a documented size (docs/reference/command-grammar.md): a plan of more than
:data:`CONFIRM_STEPS` run steps, a ``predict --map`` of more than :data:`CONFIRM_POINTS` points
(about 1 s each) or a ``sweep`` of more than :data:`CONFIRM_SWEEP_POINTS` (about 10 ms each) asks
first, so a range typed with the wrong meaning (a step for a count) is seen before it runs.
``--yes`` skips the question; without a terminal to ask on, the command refuses in one line.
"""

from __future__ import annotations

import argparse
import sys

from labkit.errors import LabkitError

CONFIRM_STEPS = 200      # labkit run: measurement steps in the plan
CONFIRM_POINTS = 500     # labkit predict --map: points to compute (~1 s each: 8 minutes)
CONFIRM_SWEEP_POINTS = 5000  # labkit sweep: points to compute (~10 ms each: about a minute)


def add_yes_argument(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument("--yes", action="store_true", help=f"go ahead without asking when {what}")


def confirm_size(n: int, limit: int, what: str, *, yes: bool, command: str) -> None:
    """Ask before ``n`` ``what`` when ``n > limit`` (LabkitError if refused or no terminal)."""
    if n <= limit or yes:
        return
    stdin = sys.stdin
    if stdin is None or not stdin.isatty():
        raise LabkitError(f"{n} {what} is more than {limit}; check the range (a:b:step=S or a:b:n=N) "
                          "and add --yes to go ahead (no terminal to ask on)")
    print(f"labkit {command}: {n} {what} (more than {limit}). Go ahead? [y/N] ", end="",
          file=sys.stderr, flush=True)
    answer = stdin.readline().strip().lower()
    if answer not in ("y", "yes"):
        raise LabkitError(f"not confirmed: {n} {what}; nothing was started")
