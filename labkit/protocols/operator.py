"""Operator input of a run: the signal a person gives by hand (the Enter key of spin-critical).

A protocol never reads stdin itself; it asks its :class:`~labkit.protocols.context.RunContext`
(``ctx.operator_signalled()``, ``ctx.discard_operator_signals()``), which asks the runner's
:class:`Operator`:

* :class:`TerminalOperator` - a line typed on an interactive stdin (the default on a real
  clock); never blocks, and is silent when stdin is not a terminal;
* :class:`NoOperator` - nobody at the keyboard (the default on a virtual clock: an emulated
  run must replay the same way whatever is typed);
* :class:`QueuedOperator` - signals given from code (another thread, a GUI, a test).
"""

from __future__ import annotations

import select
import sys
import threading
from typing import Any, Protocol


class Operator(Protocol):
    def signalled(self) -> bool: ...

    def discard(self) -> None: ...


def operator_pressed_enter() -> bool:
    """True if a line is waiting on an interactive stdin (never blocks; False when not a TTY)."""
    try:
        if not sys.stdin.isatty():
            return False
        ready, _, _ = select.select([sys.stdin], [], [], 0)
        if ready:
            sys.stdin.readline()
            return True
    except (OSError, ValueError):
        pass
    return False


def discard_pending_keys() -> None:
    """Throw away lines typed before now on an interactive stdin (never blocks).

    An Enter pressed while the rotor was still settling would otherwise sit in the terminal
    buffer and end the next trial the moment it starts, before any spin was seen."""
    try:
        if not sys.stdin.isatty():
            return
        while select.select([sys.stdin], [], [], 0)[0]:
            if not sys.stdin.readline():
                return
    except (OSError, ValueError):
        pass


class TerminalOperator:
    """The Enter key on the terminal ``sys.stdin`` is at the time of asking."""

    def signalled(self) -> bool:
        return operator_pressed_enter()

    def discard(self) -> None:
        discard_pending_keys()


class NoOperator:
    """Nobody signals."""

    def signalled(self) -> bool:
        return False

    def discard(self) -> None:
        return None


class QueuedOperator:
    """Signals given by :meth:`signal` (thread-safe), each seen once."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pending = 0

    def signal(self) -> None:
        with self._lock:
            self._pending += 1

    def signalled(self) -> bool:
        with self._lock:
            if self._pending:
                self._pending -= 1
                return True
            return False

    def discard(self) -> None:
        with self._lock:
            self._pending = 0


def default_operator(clock: Any) -> Operator:
    """The terminal on a real clock, nobody on a virtual one."""
    return NoOperator() if getattr(clock, "is_virtual", False) else TerminalOperator()
