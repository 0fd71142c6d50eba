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

A write with no counterpart within the window that the recording sent later (within
:data:`HELD_UP_S`) waits for that time: the recording's program was held up there. Any other
write with no recorded counterpart within the window raises
:class:`~labkit.errors.ReplayMismatch` naming the port, the time, what was sent and what the
recording holds around it. :meth:`FaithfulSerial.report` counts what was matched how.
"""

from __future__ import annotations

import bisect
import heapq
import threading
from typing import Any

from labkit.errors import ReplayMismatch
from labkit.io.cassette import Cassette, load_cassette
from labkit.io.clocked import LINE_SETTINGS, REAL_POLL_S, VIRTUAL_POLL_S, ClockedSerial, poll_step
from labkit.io.faithful_sessions import DeviceBytes, FaithfulSession, faithful_sessions
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
    """A port serving a real-clock cassette faithfully (see the module docstring)."""

    def __init__(self, *args, **kwargs) -> None:
        self.cassette: Cassette | None = None
        self.port_name = ""
        self.stream = False
        self.setpoints = False
        self.window = WINDOW_S
        self.origin: float | None = None
        self.sessions: list[FaithfulSession] = []
        self._next_session = 0
        self._session: FaithfulSession | None = None
        self._times: list[float] = []
        self._due: list[tuple[float, int]] = []   # (arrival time, device item) heap
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
        if self.cassette is None:
            spec = parse_replay_url(self.portstr)
            self.stream, self.setpoints = spec.stream, spec.setpoints
            default = SETPOINT_WINDOW_S if self.setpoints else WINDOW_S
            self.window = spec.window if spec.window is not None else default
            self.cassette = load_cassette(spec.cassette)
            self.port_name = self.cassette.port
            origin = self.cassette.header.get("clock_origin")
            if not isinstance(origin, int | float):  # an older cassette: aligned at its open
                first_open = next((e["t"] for e in self.cassette.events
                                   if e["dir"] == "ctl" and e.get("event") == "open"), 0.0)
                origin = clock.now() - float(first_open)
            self.origin = float(origin)
            self.sessions = faithful_sessions(self.cassette, self.origin, self.stream)
        if self._next_session >= len(self.sessions):
            raise ReplayMismatch(
                f"replay port {self.port_name!r} ({self.cassette.path}): opened "
                f"{self._next_session + 1} times but the recording opened it {len(self.sessions)} time(s)")
        session = self.sessions[self._next_session]
        self._next_session += 1
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

    def _start_session(self, session: FaithfulSession) -> None:
        self._session = session
        self._times = [w.t for w in session.writes]
        self._buffer = bytearray()
        self._held: list[int] = []
        self._dead = None
        first_write = session.writes[0].before if session.writes else len(session.device)
        now = self._resolve_clock().now()
        # on a polled port, what the device said before the first command (a power-on
        # banner) was there when the program began to talk
        self._due = [(min(session.device[i].t, now) if not self.stream and i < first_write
                      else session.device[i].t, i) for i in session.unsolicited]
        heapq.heapify(self._due)

    def _check_settings(self, session: FaithfulSession) -> None:
        recorded = (session.open_event or {}).get("serial") or {}
        actual = self.settings_summary()
        for key in LINE_SETTINGS:
            if key in recorded and recorded[key] != actual[key]:
                raise ReplayMismatch(
                    f"replay port {self.port_name!r} ({self._path()}): opened with {key}="
                    f"{actual[key]!r} but the recording used {key}={recorded[key]!r}")

    def _path(self) -> str:
        return str(self.cassette.path) if self.cassette else self.portstr

    def close(self) -> None:  # what was not sent again is counted (report), not an error
        self.is_open = False

    def report(self) -> dict[str, Any]:
        """What this port's replay matched: writes identical / near / not repeated, replies dropped."""
        writes = [w for s in self.sessions for w in s.writes]
        count = {state: sum(1 for w in writes if w.state == state)
                 for state in ("identical", "near", "pending")}
        return {"port": self.port_name, "recorded_writes": len(writes), "identical": count["identical"],
                "near": count["near"], "repeats": self._repeats, "not_repeated": count["pending"],
                "held_up": self._held_writes + self._stalls}

    # -- the time line ------------------------------------------------------------------
    def _arrive(self, now: float) -> None:
        """Move every device item due by ``now`` into the input buffer (or kill the port)."""
        session = self._session
        assert session is not None
        while self._due and self._due[0][0] <= now + TIME_EPS and self._dead is None:
            due, index = heapq.heappop(self._due)
            item = session.device[index]
            if item.gate is not None and self._held_back(item, now):
                self._held.append(index)  # not before the command it may answer (stream ports)
                continue
            self._due_now(index, due)
        for index in [i for i in self._held if not self._held_back(session.device[i], now)]:
            self._held.remove(index)
            self._due_now(index, now)

    def _held_back(self, item: DeviceBytes, now: float) -> bool:
        """A stream port's bytes recorded within the window after a write wait for that write
        (the reply to a configuration command), at most the window past their time."""
        assert self._session is not None and item.gate is not None
        write = self._session.writes[item.gate]
        return write.state == "pending" and item.t - write.t <= self.window and now < item.t + self.window

    def _next_arrival(self) -> float | None:
        return self._due[0][0] if self._due and self._dead is None else None
    def _raise_if_dead(self) -> None:
        if self._dead is not None and not self._buffer:
            raise rebuild_error(self._dead)

    # -- writes -------------------------------------------------------------------------
    def write(self, data: bytes) -> int:
        self._require_open()
        data = bytes(data)
        clock = self._resolve_clock()
        now = clock.now()
        later = self._held_up(data, now)
        if later is not None and clock.is_virtual:
            self._held_writes += 1
            clock.sleep_until(later)  # the recording's program sent it then: it was held up
        with self._lock:
            now = clock.now()
            self._arrive(now)
            if self._dead is not None:
                raise rebuild_error(self._dead)
            index, how = self._match(data, now)
            if index is None:
                raise ReplayMismatch(self._mismatch_text(data, now))
            session = self._session
            assert session is not None  # an open port is in one of the recording's sessions
            first = session.writes[index].state == "pending"
            self._accept(index, how, now)
            stalled = self._stall(index) if first and not self.setpoints else 0.0
        if stalled > 0 and clock.is_virtual:
            self._stalls += 1
            clock.sleep(stalled)  # the recording's program stood still here (see _stall)
        return len(data)

    def _stall(self, index: int) -> float:
        """How long the recording's program stood still after this write: its reply took longer
        than this command's typical reply by more than :data:`STALL_S` (a loaded PC did not run
        the reading thread). The replay stands still as long, so the driver, on the replay's
        clock, does not time out and send the command again where the recording's did not."""
        session = self._session
        assert session is not None
        write = session.writes[index]
        if not write.replies:
            return 0.0
        typical = session.typical_latency.get(write.data)
        latency = session.device[write.replies[0]].t - write.t
        extra = latency - typical if typical is not None else 0.0
        return extra if extra > STALL_S else 0.0

    def _held_up(self, data: bytes, now: float) -> float | None:
        """When a write has no recorded counterpart within the window but the recording sent
        the same bytes later (within :data:`HELD_UP_S`), the time it did: the recording's
        program was held up there (its thread waited for a lock the control loop held while a
        motor reply was late), and the replay waits as it did."""
        session = self._session
        assert session is not None
        lo = bisect.bisect_left(self._times, now - self.window)
        hi = bisect.bisect_right(self._times, now + self.window)
        # an instrument's poll is served once (each recorded reply counts in an average); a
        # motor controller's keep-alives and status polls may repeat
        for w in session.writes[lo:hi]:
            if w.data == data and (self.setpoints or w.state == "pending"):
                return None
            if self.setpoints and not w.replies and same_command(w.data, data):
                return None
        end = bisect.bisect_right(self._times, now + HELD_UP_S)
        later = next((w.t for w in session.writes[hi:end] if w.data == data and w.state == "pending"), None)
        return None if later is None else later - self.window / 2
    def _match(self, data: bytes, now: float) -> tuple[int | None, str]:
        """The recorded write within the window with the same bytes: on a setpoint port the
        nearest (one not matched yet wins a tie; an earlier match again is a keep-alive or
        status poll sent more often than recorded), else the earliest not matched yet (an
        instrument's polls are answered in the recorded order), else the nearest; on a setpoint
        port then the nearest write of the same command with another value that had no reply."""
        session = self._session
        assert session is not None
        lo = bisect.bisect_left(self._times, now - self.window)
        hi = bisect.bisect_right(self._times, now + self.window)
        # sort keys: (distance in time, served already, index) for a motor controller's write,
        # (served already, time or distance, index) for an instrument's poll
        same: tuple[float, float, int] | None = None
        near: tuple[float, float, int] | None = None
        for i in range(lo, hi):
            write = session.writes[i]
            # a motor controller's write: the nearest; an instrument's poll: the earliest not
            # served yet (its replies keep the recording's order and pace)
            pending = write.state == "pending"
            key: tuple[float, float, int] = ((abs(write.t - now), not pending, i) if self.setpoints
                   else (not pending, write.t if pending else abs(write.t - now), i))
            if write.data == data:
                same = key if same is None or key < same else same
            elif self.setpoints and not write.replies and same_command(write.data, data):
                near = key if near is None or key < near else near
        if same is not None:
            return same[2], "identical"
        if near is not None:
            return near[2], "near"
        return None, ""

    def _accept(self, index: int, how: str, now: float) -> None:
        session = self._session
        assert session is not None
        write = session.writes[index]
        first = write.state == "pending"
        if first:
            write.state = how
        else:
            self._repeats += 1
        if self.stream:  # bytes held back for this write come after it
            for i in [i for i in self._held if session.device[i].gate == index]:
                self._held.remove(i)
                heapq.heappush(self._due, (now + session.device[i].t - write.t, i))
        else:  # what the device said before this command was read before it
            early = [(t, i) for t, i in self._due if i < write.before]
            if early:
                self._due = [(t, i) for t, i in self._due if i >= write.before]
                heapq.heapify(self._due)
                for _, i in sorted(early, key=lambda e: e[1]):
                    self._due_now(i, now)
        for item in write.replies:
            # an instrument's reply arrives whole with its first bytes: lines the recording's
            # program read only later (a stale duplicate it dropped before its next command)
            # must not turn up after that command
            recorded = session.device[item if self.setpoints else write.replies[0]].t
            if self.setpoints:
                arrive = now + min(recorded - write.t, STATUS_REPLY_S)
            elif first:
                arrive = reply_time(now, write.t, recorded)
            else:
                arrive = now + recorded - write.t
            heapq.heappush(self._due, (arrive, item))

    def _due_now(self, index: int, at: float) -> None:
        """Device item ``index`` arrives at ``at`` (the newest arrival is what ``read_at``
        reports: the recording's read of it was no earlier)."""
        assert self._session is not None
        item = self._session.device[index]
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
        lo = bisect.bisect_left(self._times, now - self.window)
        hi = bisect.bisect_right(self._times, now + self.window)
        around = session.writes[lo:hi]
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
