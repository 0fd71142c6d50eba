"""A real-clock cassette put on the recording's time line, for
:class:`labkit.io.faithful_port.FaithfulSerial`: each open/close session's writes (with the
thread that sent them) and device bytes, each reply paired with the write it answers, and the
typical latency of each command's reply (docs/decisions/0019-faithful-replay.md)."""

from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Any

from labkit.io.cassette import Cassette


@dataclass
class RecordedWrite:
    t: float          # on the recording's clock
    data: bytes
    line: int
    call: str
    before: int = 0   # device items recorded before it
    thread: str | None = None
    replies: list[int] = field(default_factory=list)  # device items answering it
    state: str = "pending"  # pending | identical | near


@dataclass
class DeviceBytes:
    t: float
    kind: str        # "rx" | "error"
    data: bytes
    event: dict[str, Any]
    gate: int | None = None  # stream port: the write recorded just before it (a reply may follow)


@dataclass
class FaithfulSession:
    """One open/close of the recorded port, on the recording's time line."""

    open_event: dict[str, Any] | None = None
    open_error: dict[str, Any] | None = None
    writes: list[RecordedWrite] = field(default_factory=list)
    device: list[DeviceBytes] = field(default_factory=list)
    unsolicited: list[int] = field(default_factory=list)
    #: write bytes -> the median time from such a write to its reply
    typical_latency: dict[bytes, float] = field(default_factory=dict)

    def measure_latencies(self) -> None:
        by_command: dict[bytes, list[float]] = {}
        for write in self.writes:
            if write.replies:
                by_command.setdefault(write.data, []).append(self.device[write.replies[0]].t - write.t)
        self.typical_latency = {data: statistics.median(times) for data, times in by_command.items()}


def _last_write_of(writes: list[RecordedWrite], thread: str | None) -> RecordedWrite | None:
    """The write a reading thread's bytes answer: its own last write (cassettes record the
    thread, ``th``; recordings without it pair a read with the port's last write)."""
    for write in reversed(writes[-64:]):
        if write.thread == thread:
            return write
    return None


def faithful_sessions(cassette: Cassette, origin: float, stream: bool) -> list[FaithfulSession]:
    """A cassette's open/close sessions with every time on the recording's clock."""
    sessions: list[FaithfulSession] = []
    current: FaithfulSession | None = None
    for event in cassette.events:
        kind = event.get("event") if event["dir"] == "ctl" else event["dir"]
        if kind == "open" or current is None:
            current = FaithfulSession(open_event=event if kind == "open" else None)
            sessions.append(current)
            if kind == "open":
                continue
        t = origin + float(event["t"])
        if kind == "tx":
            current.writes.append(RecordedWrite(t, event["bytes"], event.get("line", 0),
                                                event.get("call", "write"), len(current.device),
                                                event.get("th")))
        elif kind == "rx" or (kind == "error" and event.get("call") != "open"):
            index = len(current.device)
            gate = len(current.writes) - 1 if stream and current.writes else None
            current.device.append(DeviceBytes(t, "rx" if kind == "rx" else "error",
                                              event.get("bytes", b""), event, gate))
            asked = None if stream or kind == "error" else _last_write_of(current.writes, event.get("th"))
            if asked is None:
                current.unsolicited.append(index)
            else:
                asked.replies.append(index)
        elif kind == "error":
            current.open_error = event
    for session in sessions:
        session.measure_latencies()
    return sessions
