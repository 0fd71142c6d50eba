"""Annotate port traffic with the driver call that caused it (the cassette's ``call`` key).

    with port_call("read_stable"):
        port.write(b"S\\r\\n")
        line = port.read_until(b"\\n")

``record://`` ports store the innermost active annotation with each event, and a strict
replay mismatch quotes it, so a diff says which driver method went astray. Annotations are
per thread and optional; without one the port operation's own name is used.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from labkit.io.clock import Clock

_local = threading.local()


@contextmanager
def port_call(name: str) -> Iterator[None]:
    """Mark every port operation inside the block as caused by ``name``."""
    stack = getattr(_local, "stack", None)
    if stack is None:
        stack = _local.stack = []
    stack.append(name)
    try:
        yield
    finally:
        stack.pop()


def current_call(default: str) -> str:
    """The innermost active annotation of this thread, else ``default``."""
    stack = getattr(_local, "stack", None)
    return stack[-1] if stack else default


def current_thread_tag() -> str | None:
    """The recording thread's name for a cassette's ``th`` key (None for the main thread):
    replies are read by the thread that sent the command, so a faithful replay pairs them
    by it when two threads share a port (a motor's keep-alive and its status queries)."""
    thread = threading.current_thread()
    if thread is threading.main_thread():
        return None
    name = thread.name
    return name[len("labkit-"):] if name.startswith("labkit-") else name


def read_time(port: object, clock: Clock) -> float:
    """When the bytes a port's last ``read`` returned were read, on ``clock``: the time a
    ``record://`` port wrote into its cassette, or a faithful replay port's arrival time
    (``read_at``), so the recording and its replay timestamp a line alike; else ``clock.now()``."""
    at = getattr(port, "read_at", None)
    return at if isinstance(at, float) else clock.now()
