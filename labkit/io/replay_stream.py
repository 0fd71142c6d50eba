"""A cassette's open/close sessions read as far as a strict or timed replay needs, no further
(:mod:`labkit.io.replay_port`; docs/decisions/0030-compact-cassettes.md).

A replay used to hold a whole cassette in memory; a 5 000-point session's motor cassette has
millions of events. :class:`RecordedSession` reads the events of one session from a shared
:class:`EventQueue` only when the replay asks for the next device item or for recorded TX bytes
it must compare, and forgets what the replay has used: memory is flat in the cassette's length
(it holds what was read ahead, the TX bytes and device items between the program's position
and the next one it asks for).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

#: bytes of written TX kept for the context of a mismatch message
TX_CONTEXT = 24


@dataclass
class DeviceItem:
    """One thing the device side delivers: an ``rx`` chunk, an ``empty`` read or an ``error``."""

    kind: str
    t: float
    gate: int  # TX bytes of this session written before it was recorded
    event: dict[str, Any]
    data: bytes = b""


class EventQueue:
    """The events of a cassette, one at a time, with a look at the next."""

    def __init__(self, events: Iterator[dict[str, Any]]) -> None:
        self._events = events
        self._next: dict[str, Any] | None = None
        self._done = False

    def peek(self) -> dict[str, Any] | None:
        if self._next is None and not self._done:
            self._next = next(self._events, None)
            self._done = self._next is None
        return self._next

    def pop(self) -> dict[str, Any] | None:
        event = self.peek()
        self._next = None
        return event


def event_kind(event: dict[str, Any]) -> str:
    """``tx``, ``rx`` or a control event's name."""
    return str(event.get("event")) if event["dir"] == "ctl" else str(event["dir"])


def is_open(event: dict[str, Any] | None) -> bool:
    return event is not None and event_kind(event) == "open"


class RecordedSession:
    """One open/close session of a cassette (the events after its ``open`` up to the next)."""

    def __init__(self, queue: EventQueue, open_event: dict[str, Any] | None) -> None:
        self.queue = queue
        self.open_event = open_event
        self.open_error: dict[str, Any] | None = None
        self.ended = False
        self.tx_read = 0                       # TX bytes of the session read so far
        self.tx_written = 0                    # ... and replayed (written by the program)
        self.tx_pending = bytearray()          # session TX [tx_written, tx_read)
        self.tx_recent = b""                   # the last TX_CONTEXT bytes before tx_written
        self.tx_marks: deque[tuple[int, str, int | None]] = deque()  # (offset, call, line) of tx events
        self.device: deque[DeviceItem] = deque()
        self.write_errors: deque[tuple[int, dict[str, Any]]] = deque()  # (gate, event)
        self._last_device: DeviceItem | None = None
        self._drained: tuple[int, int, DeviceItem | None, int] | None = None

    # -- reading ahead ------------------------------------------------------------------
    def read_one(self) -> bool:
        """Take the session's next event; False at its end (the next open, or the file's end)."""
        if self.ended:
            return False
        event = self.queue.peek()
        if event is None or is_open(event):
            self.ended = True
            return False
        self.queue.pop()
        kind, gate = event_kind(event), self.tx_read
        if kind == "tx":
            self.tx_marks.append((gate, str(event.get("call", "write")), event.get("line")))
            self.tx_pending += event["bytes"]
            self.tx_read += len(event["bytes"])
        elif kind == "rx":
            self._last_device = DeviceItem("rx", event["t"], gate, event, event["bytes"])
            self.device.append(self._last_device)
        elif kind == "short_read":
            last = self._last_device
            if (last is not None and last.kind == "rx" and last.gate == gate
                    and event.get("got") == len(last.data) and "short" not in last.event):
                last.event["short"] = True
            elif not event.get("got"):
                self.device.append(DeviceItem("empty", event["t"], gate, event))
        elif kind == "error":
            call = event.get("call", "")
            if call == "open":
                self.open_error = event
            elif call == "write":
                self.write_errors.append((gate, event))
            else:
                self.device.append(DeviceItem("error", event["t"], gate, event))
        return True

    def start(self) -> None:
        """Read the events that come before any traffic (the open's own error)."""
        while (self.open_error is None and not self.device and not self.tx_read
               and not self.write_errors and self.read_one()):
            pass

    def fill_tx(self, upto: int) -> None:
        """Read until the session's TX holds ``upto`` bytes (or it ends), and a write error
        recorded right after the last of them."""
        while self.tx_read < upto and self.read_one():
            pass
        following = self.queue.peek()
        if (not self.ended and following is not None and event_kind(following) == "error"
                and following.get("call") == "write"):
            self.read_one()

    def next_device(self) -> DeviceItem | None:
        while not self.device and self.read_one():
            pass
        return self.device[0] if self.device else None

    # -- the replay's moves -------------------------------------------------------------
    def expected(self, size: int) -> bytes:
        """The next ``size`` recorded TX bytes (fewer at the session's end)."""
        self.fill_tx(self.tx_written + size)
        return bytes(self.tx_pending[:size])

    def next_write_error(self) -> tuple[int, dict[str, Any]] | None:
        return self.write_errors[0] if self.write_errors else None

    def written(self, size: int) -> None:
        """The program wrote the next ``size`` recorded TX bytes."""
        self.tx_recent = (self.tx_recent + bytes(self.tx_pending[:size]))[-TX_CONTEXT:]
        del self.tx_pending[:size]
        self.tx_written += size
        while len(self.tx_marks) >= 2 and self.tx_marks[1][0] <= self.tx_written - TX_CONTEXT:
            self.tx_marks.popleft()

    def tx_slice(self, start: int, end: int) -> bytes:
        """The session's TX bytes [start, end) (start no more than TX_CONTEXT before tx_written)."""
        self.fill_tx(end)
        before = self.tx_recent[max(0, len(self.tx_recent) - (self.tx_written - start)):] \
            if start < self.tx_written else b""
        after = self.tx_pending[max(0, start - self.tx_written):max(0, end - self.tx_written)]
        return before + bytes(after)

    def mark_at(self, offset: int) -> tuple[int, str, int | None]:
        """The tx event whose bytes hold ``offset`` (offset, call, line)."""
        found: tuple[int, str, int | None] = (0, "write", None)
        for mark in self.tx_marks:
            if mark[0] > offset:
                break
            found = mark
        return found

    def drain(self) -> tuple[int, int, DeviceItem | None, int]:
        """Read the session to its end, keeping nothing: (TX bytes not written, device items not
        delivered, the first of them, write errors not reached). Asked again, the same answer."""
        if self._drained is None:
            first = self.device[0] if self.device else None
            items = len(self.device)
            self.device.clear()
            while self.read_one():
                if self.device:
                    first = first or self.device[0]
                    items += len(self.device)
                    self.device.clear()
                del self.tx_pending[TX_CONTEXT:]   # the first bytes stay for the message
                while len(self.tx_marks) > 8:
                    self.tx_marks.pop()
            self._drained = (self.tx_read - self.tx_written, items, first, len(self.write_errors))
        return self._drained
