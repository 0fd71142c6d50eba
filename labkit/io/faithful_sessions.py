"""A cassette's open/close sessions as a faithful replay serves them (:mod:`labkit.io.faithful_port`),
read as the replay's clock goes, no further (docs/decisions/0030-compact-cassettes.md).

Per open/close of the recorded port: the writes the program made and the device bytes that
answered each (or came unasked), every time on the recording's clock. A
:class:`FaithfulSession` reads its events from the cassette only up to a time the port asks for
(:meth:`FaithfulSession.read_until`: the replay's clock plus :data:`LOOKAHEAD_S`) and forgets
the writes that lie more than the match window behind the clock
(:meth:`FaithfulSession.forget_before`), counting how each was matched. Memory holds the
writes of a few seconds around the clock and the device bytes not delivered yet: flat in the
session's length. The one number taken from the whole cassette, each polled command's typical
reply latency (the median, :func:`typical_latencies`), is found by a first pass that keeps 8
bytes per reply (an ``array`` of latencies) and then only the medians.
"""

from __future__ import annotations

import bisect
import statistics
from array import array
from collections import Counter, deque
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from labkit.io.cassette import CassetteReader
from labkit.io.replay_stream import EventQueue, event_kind, is_open

#: how far (s) past the clock a session is read: beyond every write a write at the clock may
#: match or wait for (labkit.io.faithful_port.SETPOINT_WINDOW_S, HELD_UP_S) and beyond a
#: stalled recording's late reply (a stall is measured when its write is matched, from the
#: reply read by then)
LOOKAHEAD_S = 10.0
#: writes older than the match window by this much (s) are forgotten
FORGET_MARGIN_S = 1.0
#: how many recent writes a reading thread's bytes are paired against (its own last write)
PAIRING_DEPTH = 64


@dataclass(eq=False)
class RecordedWrite:
    t: float          # on the recording's clock
    data: bytes
    line: int
    call: str
    index: int        # the session's write number
    before: int = 0   # device items recorded before it
    thread: str | None = None
    replies: list[DeviceBytes] = field(default_factory=list)  # device items answering it
    state: str = "pending"  # pending | identical | near
    accepted_at: float | None = None  # the replay's clock when it was first matched


@dataclass(eq=False)
class DeviceBytes:
    t: float
    kind: str        # "rx" | "error"
    data: bytes
    event: dict[str, Any]
    index: int       # the session's device item number
    gate: RecordedWrite | None = None   # stream port: the write recorded just before it
    asked: RecordedWrite | None = None  # polled port: the write it answers (None: unasked)


class FaithfulSession:
    """One open/close of the recorded port, on the recording's time line, read as far as asked."""

    def __init__(self, queue: EventQueue, open_event: dict[str, Any] | None, origin: float, stream: bool,
                 typical_latency: dict[bytes, float] | None = None) -> None:
        self.queue, self.origin, self.stream = queue, origin, stream
        self.open_event = open_event
        self.open_error: dict[str, Any] | None = None
        #: the writes read and not forgotten, in file order, and their times
        self.writes: list[RecordedWrite] = []
        self.times: list[float] = []
        self.base = 0                    # the write number of writes[0]
        self.write_count = 0
        self.device_count = 0
        self.ended = False
        self.frontier = float("-inf")    # the time of the last event read
        #: write bytes -> the median time from such a write to its reply (typical_latencies)
        self.typical_latency: dict[bytes, float] = typical_latency or {}
        self.latencies: dict[bytes, array] | None = None  # collected by the first pass only
        self.forgotten: Counter[str] = Counter()          # states of the writes forgotten
        self._recent: deque[RecordedWrite] = deque(maxlen=PAIRING_DEPTH)

    # -- reading --------------------------------------------------------------------------
    def read_one(self) -> DeviceBytes | None:
        """Take the session's next event: the device item it holds, else None; at the session's
        end (the next open, or the file's end) :attr:`ended` turns True."""
        if self.ended:
            return None
        event = self.queue.peek()
        if event is None or is_open(event):
            self.ended = True
            return None
        self.queue.pop()
        kind = event_kind(event)
        t = self.origin + float(event["t"])
        self.frontier = max(self.frontier, t)
        if kind == "tx":
            write = RecordedWrite(t, event["bytes"], event.get("line", 0), event.get("call", "write"),
                                  self.write_count, self.device_count, event.get("th"))
            self.write_count += 1
            self.writes.append(write)
            self.times.append(t)
            self._recent.append(write)
        elif kind == "rx" or (kind == "error" and event.get("call") != "open"):
            return self._device(t, kind, event)
        elif kind == "error":
            self.open_error = event
        return None

    def _device(self, t: float, kind: str, event: dict[str, Any]) -> DeviceBytes:
        gate = self._recent[-1] if self.stream and self._recent else None
        item = DeviceBytes(t, "rx" if kind == "rx" else "error", event.get("bytes", b""), event,
                           self.device_count, gate)
        self.device_count += 1
        if not self.stream and kind == "rx":
            item.asked = self._last_write_of(event.get("th"))
            if item.asked is not None:
                if not item.asked.replies and self.latencies is not None:
                    self.latencies.setdefault(item.asked.data, array("d")).append(t - item.asked.t)
                item.asked.replies.append(item)
        return item

    def _last_write_of(self, thread: str | None) -> RecordedWrite | None:
        """The write a reading thread's bytes answer: its own last write (cassettes record the
        thread, ``th``; recordings without it pair a read with the port's last write)."""
        for write in reversed(self._recent):
            if write.thread == thread:
                return write
        return None

    def read_until(self, t: float) -> Iterator[DeviceBytes]:
        """Read the events up to the first one after ``t`` (clock time); yield their device items."""
        while self.frontier <= t and not self.ended:
            got = self.read_one()
            if got is not None:
                yield got

    def read_to_first_write(self) -> Iterator[DeviceBytes]:
        """Read until the session's first write (or its end): what the device said before it."""
        while not self.write_count and not self.ended:
            got = self.read_one()
            if got is not None:
                yield got

    def forget_before(self, t: float) -> None:
        """Forget the writes recorded before ``t``, counting how each was matched."""
        cut = bisect.bisect_left(self.times, t)
        if cut > 256 or (cut and cut * 2 > len(self.times)):  # in batches: a list's head is costly
            self.forgotten.update(w.state for w in self.writes[:cut])
            del self.writes[:cut]
            del self.times[:cut]
            self.base += cut

    def skip_rest(self) -> None:
        """Read to the session's end keeping nothing (its writes counted as not matched)."""
        while not self.ended:
            self.read_one()
            if len(self.writes) > 1024:
                self.forget_before(float("inf"))
        self.forget_before(float("inf"))

    # -- windows of writes -------------------------------------------------------------
    def within(self, lo: float, hi: float, after: bool = False) -> list[RecordedWrite]:
        """The writes recorded in [lo, hi] (``after``: (lo, hi]) that are still held (read and
        not forgotten)."""
        start = (bisect.bisect_right if after else bisect.bisect_left)(self.times, lo)
        return self.writes[start:bisect.bisect_right(self.times, hi)]

    def states(self) -> Counter[str]:
        """How the writes read so far were matched (forgotten and held)."""
        return self.forgotten + Counter(w.state for w in self.writes)


def open_sessions(reader: CassetteReader, origin: float, stream: bool,
                  latencies: list[dict[bytes, float]] | None = None) -> Iterator[FaithfulSession]:
    """The cassette's sessions one after the other, each read only as far as it is asked (read
    the one before to its end, :meth:`FaithfulSession.skip_rest`, before taking the next).
    ``latencies``: per session, the typical reply latency of each command
    (:func:`typical_latencies`)."""
    queue = EventQueue(iter(reader))
    number = 0
    while True:
        first = queue.peek()
        if first is None or (number and not is_open(first)):
            return
        open_event = queue.pop() if is_open(first) else None
        typical = latencies[number] if latencies is not None and number < len(latencies) else None
        yield FaithfulSession(queue, open_event, origin, stream, typical)
        number += 1


def typical_latencies(path: str | Path) -> list[dict[bytes, float]]:
    """Per session of a polled port's cassette, each command's median time from a write to
    its first reply (a first pass over the cassette, keeping the latencies as 8-byte floats)."""
    out: list[dict[bytes, float]] = []
    for session in open_sessions(CassetteReader(path), 0.0, stream=False):
        session.latencies = {}
        while not session.ended:
            session.read_one()
            if len(session.writes) > 1024:  # only the last PAIRING_DEPTH writes pair replies
                session.forget_before(float("inf"))
        out.append({data: statistics.median(times) for data, times in session.latencies.items()})
        session.latencies = None
    return out
