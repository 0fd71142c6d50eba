"""``replay://<cassette>?mode=faithful``: a real-clock recording served as a device would.

A session recorded on the real clock cannot be replayed byte for byte: how many keep-alives
and status polls went out, and in which order two threads wrote them, depended on the
scheduler (docs/decisions/0019-faithful-replay.md). This port serves such a cassette as the
recorded device behaved, on one time line:

* **Time line.** ``t`` of every event is put on the recording's clock (the header's
  ``clock_origin``; a cassette without it is aligned at its open, as ``mode=timed`` does).
  A replay on a :class:`~labkit.io.clock.VirtualClock` started at the same reading sees
  the device's bytes at their recorded times.
* **Bytes arrive, reads take them.** Device bytes go into an input buffer at their time and
  reads take what is there (pyserial's semantics: ``read(n)`` waits for ``n`` bytes or the
  timeout, ``in_waiting`` counts them). A recorded timeout needs no replaying: a read that
  finds nothing times out by itself.
* **Writes are matched by content** within ``window`` seconds (default :data:`WINDOW_S`,
  :data:`SETPOINT_WINDOW_S` on a motor controller's port): an instrument's poll to the
  earliest recorded one of the same bytes not answered yet, a motor controller's write to
  the nearest one not matched yet; else again (a poll sent more often than recorded: its
  reply is served again). Recorded writes never matched (a keep-alive or poll the replay
  sent less often) are counted, not an error. On a ``setpoints=1`` port a write may also
  match a recorded write of the same command with another value (a duty computed from a
  tick a few ms apart).
* **Replies follow their command.** On a polled port (default) bytes recorded after a write
  are that write's reply (read by the thread that wrote, ``th``): they arrive at their
  recorded time, or at once if the program asked later (:func:`reply_time`); a repeated
  poll's after its recorded latency; a motor controller's (``setpoints=1``: its status is
  polled by the control loop, whose ticks must not wait for the recording's) after its
  recorded latency, at most :data:`STATUS_REPLY_S`. What the device said before a command
  (a power-on banner) is there before the command. On a ``stream=1`` port (a tachometer)
  every byte arrives at its recorded time, a configuration reply not before its command.
* **Errors at their time.** A recorded error (an unplug) kills the port at its recorded time:
  bytes already in the buffer are still read, then every call raises the recorded error.
* **Read times.** ``read_at`` is when the newest bytes a read returned arrived: the time the
  recording read them (a ``record://`` port's ``read_at``), so drivers timestamp a line
  (:func:`labkit.io.calls.read_time`) as the recording did, not at their next poll.

The cassette is read as the clock goes (:mod:`labkit.io.faithful_sessions`): to
:data:`~labkit.io.faithful_sessions.LOOKAHEAD_S` past the clock, its writes forgotten once the
window has left them behind, so memory is flat in the recording's length.

A write with no counterpart within the window that the recording sent later (within
:data:`HELD_UP_S`) waits for that time: the recording's program was held up there. Any other
write with no recorded counterpart within the window raises
:class:`~labkit.errors.ReplayMismatch` naming the port, the time, what was sent and what the
recording holds around it. :meth:`FaithfulSerial.report` counts what was matched how.
"""

from __future__ import annotations

import heapq
import itertools
import threading
from collections import Counter
from collections.abc import Iterator
from typing import Any

from labkit.errors import ReplayMismatch
from labkit.io.cassette import CassetteReader
from labkit.io.clocked import LINE_SETTINGS, REAL_POLL_S, VIRTUAL_POLL_S, ClockedSerial, poll_step
from labkit.io.faithful_sessions import (
    FORGET_MARGIN_S,
    LOOKAHEAD_S,
    DeviceBytes,
    FaithfulSession,
    RecordedWrite,
    open_sessions,
    typical_latencies,
)
from labkit.io.replay_port import rebuild_error, render_bytes
from labkit.io.urls import parse_replay_url

#: how far (s) a replayed write may lie from the recorded write it is matched to
WINDOW_S = 0.5
#: the same on a motor controller's port: its writes change nothing the replay reads (the
#: tachometer is recorded), and a loaded recording spread one tick's status queries over
#: more than a second
SETPOINT_WINDOW_S = 2.0
#: the longest (s) a reply is held back beyond its recorded latency to arrive at its recorded time
#: (below the 0.5 s after which a balance driver sends its poll again)
HOLD_S = 0.4
#: a motor controller's status reply arrives at most this long (s) after its query: a later
#: recorded reply was late because the recording's reading thread waited for the CPU (a
#: loaded lab PC), which the replay does not, and would miss the driver's reply timeout
STATUS_REPLY_S = 0.02
#: how far (s) ahead of the recording a write may find the recorded one it waits for (a
#: recorded program held up for about a motor reply's timeout, 1 s on a loaded PC; a poll
#: more than the recording made at the end of an averaging window finds the next step's
#: polls seconds later, and is answered again instead)
HELD_UP_S = 1.5
#: a reply later than its command's typical reply by more than this (s) was a stalled program
STALL_S = 0.1
TIME_EPS = 1e-9


def reply_time(sent: float, recorded_sent: float, recorded_reply: float) -> float:
    """When a reply arrives in a faithful replay: at its recorded time, so the program's polls
    keep the recording's pace (its own time, spent computing and polling, is not on the virtual
    clock); at once when the program asks later than it did; held back at most :data:`HOLD_S`
    beyond the recorded latency when it asks earlier (a driver's reply timeout is 0.1 s)."""
    latency = recorded_reply - recorded_sent
    return min(max(recorded_reply, sent + TIME_EPS), sent + latency + HOLD_S)


def same_command(a: bytes, b: bytes) -> bool:
    """Two motor-controller writes of the same command with other values: the same length and
    the same leading bytes (the command byte; start byte, length and command id of a framed
    packet such as a VESC's)."""
    head = 3 if len(a) >= 6 else 1
    return len(a) == len(b) and a[:head] == b[:head]


class FaithfulSerial(ClockedSerial):
    """A port serving a real-clock cassette faithfully (see the module docstring), read as the
    clock goes (:mod:`labkit.io.faithful_sessions`)."""

    def __init__(self, *args, **kwargs) -> None:
        self.cassette_path = ""
        self.port_name = ""
        self.stream = False
        self.setpoints = False
        self.window = WINDOW_S
        self.origin: float | None = None
        self._sessions: Iterator[FaithfulSession] | None = None
        self._used: list[FaithfulSession] = []  # the sessions opened so far (their counts)
        self._session: FaithfulSession | None = None
        self._due: list[tuple[float, int, int, DeviceBytes]] = []  # (arrival, item, seq, item) heap
        self._seq = itertools.count()
        self._held: list[DeviceBytes] = []
        self._buffer = bytearray()
        self._dead: dict[str, Any] | None = None
        #: when the bytes the last read returned arrived (labkit.io.calls.read_time)
        self.read_at: float | None = None
        self._arrived_at: float | None = None
        self._repeats = 0
        self._held_writes = 0
        self._stalls = 0
        self._lock = threading.RLock()
        super().__init__(*args, **kwargs)

    # -- life cycle ---------------------------------------------------------------------
    def open(self) -> None:
        self._require_openable()
        clock = self._resolve_clock()
        if self._sessions is None:
            self._sessions = self._load(clock.now())
        if self._session is not None:
            self._session.skip_rest()
        session = next(self._sessions, None)
        if session is None:
            raise ReplayMismatch(
                f"replay port {self.port_name!r} ({self._path()}): opened "
                f"{len(self._used) + 1} times but the recording opened it {len(self._used)} time(s)")
        self._used.append(session)
        origin = self.origin
        assert origin is not None  # set with the cassette on the first open, above
        opened_at = origin + float((session.open_event or {}).get("t", 0.0))
        if clock.is_virtual and clock.now() < opened_at:
            clock.sleep_until(opened_at)  # the recording opened it then (imports, other ports)
        self._start_session(session)
        self._check_settings(session)
        if session.open_error is not None:
            raise rebuild_error(session.open_error)
        self.is_open = True

    def _load(self, now: float) -> Iterator[FaithfulSession]:
        """The cassette's sessions, read as the replay goes (a polled port's typical reply
        latencies first, from a pass over the whole cassette)."""
        spec = parse_replay_url(self.portstr)
        self.stream, self.setpoints = spec.stream, spec.setpoints
        default = SETPOINT_WINDOW_S if self.setpoints else WINDOW_S
        self.window = spec.window if spec.window is not None else default
        reader = CassetteReader(spec.cassette)
        self.cassette_path, self.port_name = str(reader.path), reader.port
        origin = reader.header.get("clock_origin")
        if not isinstance(origin, int | float):  # an older cassette: aligned at its open
            first_open = next((e["t"] for e in CassetteReader(spec.cassette)
                               if e["dir"] == "ctl" and e.get("event") == "open"), 0.0)
            origin = now - float(first_open)
        self.origin = float(origin)
        polled = not (self.stream or self.setpoints)  # only a polled port's stalls are measured
        return open_sessions(reader, self.origin, self.stream,
                             typical_latencies(spec.cassette) if polled else None)

    def _start_session(self, session: FaithfulSession) -> None:
        self._session = session
        self._buffer = bytearray()
        self._held = []
        self._dead = None
        self._due = []
        now = self._resolve_clock().now()
        if not self.stream:
            # on a polled port, what the device said before the first command (a power-on
            # banner) was there when the program began to talk
            for item in session.read_to_first_write():
                self._push(min(item.t, now), item)
        self._advance(now)

    def _check_settings(self, session: FaithfulSession) -> None:
        recorded = (session.open_event or {}).get("serial") or {}
        actual = self.settings_summary()
        for key in LINE_SETTINGS:
            if key in recorded and recorded[key] != actual[key]:
                raise ReplayMismatch(
                    f"replay port {self.port_name!r} ({self._path()}): opened with {key}="
                    f"{actual[key]!r} but the recording used {key}={recorded[key]!r}")

    def _path(self) -> str:
        return self.cassette_path or self.portstr

    def close(self) -> None:  # what was not sent again is counted (report), not an error
        self.is_open = False

    def report(self) -> dict[str, Any]:
        """What this port's replay matched: writes identical / near / not repeated, replies
        dropped. Reads the rest of the cassette (its writes not sent again): call it last."""
        count: Counter[str] = Counter()
        with self._lock:
            for session in self._used:
                session.skip_rest()
                count += session.states()
            # the sessions never opened, each read to its end before the next is taken
            for session in self._sessions or ():
                session.skip_rest()
                count += session.states()
        return {"port": self.port_name, "recorded_writes": sum(count.values()),
                "identical": count["identical"], "near": count["near"], "repeats": self._repeats,
                "not_repeated": count["pending"], "held_up": self._held_writes + self._stalls}

    def holding(self) -> dict[str, int]:
        """What the port holds in memory now: recorded writes (read ahead of the clock and not
        yet left behind by the window) and device items scheduled; flat in the cassette's length."""
        with self._lock:
            writes = len(self._session.writes) if self._session is not None else 0
            return {"writes": writes, "due": len(self._due) + len(self._held)}

    # -- the time line ------------------------------------------------------------------
    def _push(self, at: float, item: DeviceBytes) -> None:
        heapq.heappush(self._due, (at, item.index, next(self._seq), item))

    def _advance(self, now: float) -> None:
        """Read the cassette to :data:`LOOKAHEAD_S` past ``now``, schedule the device bytes read
        (unasked ones at their time, a reply to a write matched already as if read with it) and
        forget the writes the window has left behind."""
        session = self._session
        assert session is not None
        for item in session.read_until(now + LOOKAHEAD_S):
            if item.asked is None:
                self._push(item.t, item)
            elif item.asked.accepted_at is not None:
                self._push(self._reply_arrival(item.asked, item, item.asked.accepted_at, True), item)
        session.forget_before(now - self.window - FORGET_MARGIN_S)

    def _arrive(self, now: float) -> None:
        """Move every device item due by ``now`` into the input buffer (or kill the port)."""
        self._advance(now)
        while self._due and self._due[0][0] <= now + TIME_EPS and self._dead is None:
            due, _, _, item = heapq.heappop(self._due)
            if item.gate is not None and self._held_back(item, now):
                self._held.append(item)  # not before the command it may answer (stream ports)
                continue
            self._due_now(item, due)
        for item in [i for i in self._held if not self._held_back(i, now)]:
            self._held.remove(item)
            self._due_now(item, now)

    def _held_back(self, item: DeviceBytes, now: float) -> bool:
        """A stream port's bytes recorded within the window after a write wait for that write
        (the reply to a configuration command), at most the window past their time."""
        write = item.gate
        assert write is not None
        return write.state == "pending" and item.t - write.t <= self.window and now < item.t + self.window

    def _next_arrival(self) -> float | None:
        """When the next device bytes arrive: the earliest scheduled, or the end of what was
        read of the cassette (bytes not read yet come after it)."""
        if self._dead is not None:
            return None
        session = self._session
        ahead = session.frontier if session is not None and not session.ended else None
        due = self._due[0][0] if self._due else None
        return min((t for t in (due, ahead) if t is not None), default=None)

    def _raise_if_dead(self) -> None:
        if self._dead is not None and not self._buffer:
            raise rebuild_error(self._dead)

    # -- writes -------------------------------------------------------------------------
    def write(self, data: bytes) -> int:
        self._require_open()
        data = bytes(data)
        clock = self._resolve_clock()
        with self._lock:
            now = clock.now()
            self._advance(now)
            later = self._held_up(data, now)
        if later is not None and clock.is_virtual:
            self._held_writes += 1
            clock.sleep_until(later)  # the recording's program sent it then: it was held up
        with self._lock:
            now = clock.now()
            self._arrive(now)
            if self._dead is not None:
                raise rebuild_error(self._dead)
            write, how = self._match(data, now)
            if write is None:
                raise ReplayMismatch(self._mismatch_text(data, now))
            first = write.state == "pending"
            self._accept(write, how, now)
            stalled = self._stall(write) if first and not self.setpoints else 0.0
        if stalled > 0 and clock.is_virtual:
            self._stalls += 1
            clock.sleep(stalled)  # the recording's program stood still here (see _stall)
        return len(data)

    def _stall(self, write: RecordedWrite) -> float:
        """How long the recording's program stood still after this write: its reply took longer
        than this command's typical reply by more than :data:`STALL_S` (a loaded PC did not run
        the reading thread). The replay stands still as long, so the driver, on the replay's
        clock, does not time out and send the command again where the recording's did not."""
        session = self._session
        assert session is not None
        if not write.replies:
            return 0.0
        typical = session.typical_latency.get(write.data)
        latency = write.replies[0].t - write.t
        extra = latency - typical if typical is not None else 0.0
        return extra if extra > STALL_S else 0.0

    def _held_up(self, data: bytes, now: float) -> float | None:
        """When a write has no recorded counterpart within the window but the recording sent
        the same bytes later (within :data:`HELD_UP_S`), the time it did: the recording's
        program was held up there (its thread waited for a lock the control loop held while a
        motor reply was late), and the replay waits as it did."""
        session = self._session
        assert session is not None
        # an instrument's poll is served once (each recorded reply counts in an average); a
        # motor controller's keep-alives and status polls may repeat
        for w in session.within(now - self.window, now + self.window):
            if w.data == data and (self.setpoints or w.state == "pending"):
                return None
            if self.setpoints and not w.replies and same_command(w.data, data):
                return None
        later = next((w.t for w in session.within(now + self.window, now + HELD_UP_S, after=True)
                      if w.data == data and w.state == "pending"), None)
        return None if later is None else later - self.window / 2

    def _match(self, data: bytes, now: float) -> tuple[RecordedWrite | None, str]:
        """The recorded write within the window with the same bytes: on a setpoint port the
        nearest (one not matched yet wins a tie; an earlier match again is a keep-alive or
        status poll sent more often than recorded), else the earliest not matched yet (an
        instrument's polls are answered in the recorded order), else the nearest; on a setpoint
        port then the nearest write of the same command with another value that had no reply."""
        session = self._session
        assert session is not None
        # sort keys: (distance in time, served already, index) for a motor controller's write,
        # (served already, time or distance, index) for an instrument's poll
        same: tuple[float, float, int, RecordedWrite] | None = None
        near: tuple[float, float, int, RecordedWrite] | None = None
        for write in session.within(now - self.window, now + self.window):
            # a motor controller's write: the nearest; an instrument's poll: the earliest not
            # served yet (its replies keep the recording's order and pace)
            pending = write.state == "pending"
            key = ((abs(write.t - now), not pending, write.index, write) if self.setpoints
                   else (not pending, write.t if pending else abs(write.t - now), write.index, write))
            if write.data == data:
                same = key if same is None or key[:3] < same[:3] else same
            elif self.setpoints and not write.replies and same_command(write.data, data):
                near = key if near is None or key[:3] < near[:3] else near
        if same is not None:
            return same[3], "identical"
        if near is not None:
            return near[3], "near"
        return None, ""

    def _reply_arrival(self, write: RecordedWrite, item: DeviceBytes, now: float, first: bool) -> float:
        """When a reply to ``write``, matched at ``now``, arrives (module docstring)."""
        # an instrument's reply arrives whole with its first bytes: lines the recording's
        # program read only later (a stale duplicate it dropped before its next command)
        # must not turn up after that command
        recorded = (item if self.setpoints else write.replies[0]).t
        if self.setpoints:
            return now + min(recorded - write.t, STATUS_REPLY_S)
        if first:
            return reply_time(now, write.t, recorded)
        return now + recorded - write.t

    def _accept(self, write: RecordedWrite, how: str, now: float) -> None:
        first = write.state == "pending"
        if first:
            write.state = how
            write.accepted_at = now
        else:
            self._repeats += 1
        if self.stream:  # bytes held back for this write come after it
            for item in [i for i in self._held if i.gate is write]:
                self._held.remove(item)
                self._push(now + item.t - write.t, item)
        else:  # what the device said before this command was read before it
            early = [e for e in self._due if e[1] < write.before]
            if early:
                self._due = [e for e in self._due if e[1] >= write.before]
                heapq.heapify(self._due)
                for entry in sorted(early, key=lambda e: (e[1], e[2])):
                    self._due_now(entry[3], now)
        for item in write.replies:
            self._push(self._reply_arrival(write, item, now, first), item)

    def _due_now(self, item: DeviceBytes, at: float) -> None:
        """Device item ``item`` arrives at ``at`` (the newest arrival is what ``read_at``
        reports: the recording's read of it was no earlier)."""
        if self._dead is not None:
            return
        if item.kind == "error":
            self._dead = item.event
        else:
            self._buffer += item.data
            self._arrived_at = at

    def _mismatch_text(self, data: bytes, now: float) -> str:
        session = self._session
        assert session is not None
        around = session.within(now - self.window, now + self.window)
        kinds: dict[bytes, int] = {}
        for w in around:
            kinds[w.data] = kinds.get(w.data, 0) + 1
        held = ", ".join(f"{render_bytes(b)} x{n}" for b, n in list(kinds.items())[:6]) or "no writes"
        t_rel = now - (self.origin or 0.0)
        line = min(around, key=lambda w: abs(w.t - now)).line if around else None
        where = f", cassette line {line}" if line else ""
        return (f"replay port {self.port_name!r} ({self._path()}): at {t_rel:.3f} s the program sent "
                f"{render_bytes(data)} but the recording holds no such command within "
                f"{self.window:g} s{where} (recorded there: {held})")

    # -- reads --------------------------------------------------------------------------
    def read(self, size: int = 1) -> bytes:
        self._require_open()
        if size <= 0:
            return b""
        clock = self._resolve_clock()
        deadline = None if self._timeout is None else clock.now() + self._timeout
        while True:
            with self._lock:
                now = clock.now()
                self._arrive(now)
                if len(self._buffer) >= size or (self._buffer and (self._timeout == 0 or self._dead)):
                    return self._take(size)
                self._raise_if_dead()
                if self._timeout == 0 or (deadline is not None and now >= deadline - TIME_EPS):
                    return self._take(size)
                arrival = self._next_arrival()
            if arrival is None and deadline is None and not clock.is_virtual:
                clock.sleep(REAL_POLL_S)
                continue
            if arrival is None and deadline is None:
                raise ReplayMismatch(f"replay port {self.port_name!r} ({self._path()}): a blocking read "
                                     "(timeout=None) after the last recorded byte would wait forever")
            target = min(t for t in (arrival, deadline) if t is not None)
            if clock.is_virtual:
                # a clock job may write (and so schedule a reply) while we wait
                clock.sleep(max(0.0, min(target - now, VIRTUAL_POLL_S * 10)))
            else:
                clock.sleep(poll_step(REAL_POLL_S, now, deadline))

    def _take(self, size: int) -> bytes:
        out = bytes(self._buffer[:size])
        self.read_at = self._arrived_at if out else None
        del self._buffer[:size]
        return out

    @property
    def in_waiting(self) -> int:
        self._require_open()
        clock = self._resolve_clock()
        with self._lock:
            self._arrive(clock.now())
            self._raise_if_dead()
            return len(self._buffer)

    def reset_input_buffer(self) -> None:
        """A recording holds only bytes that were read, none that a reset dropped: nothing to drop."""
        self._require_open()
        with self._lock:
            self._raise_if_dead()
