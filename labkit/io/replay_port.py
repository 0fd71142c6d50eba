"""``replay://<cassette>?mode=strict|timed``: a recorded port, served back byte-exact
(``mode=faithful``, for real-clock recordings: :mod:`labkit.io.faithful_port`).

* Every read call returns exactly the next recorded chunk (what the recorded read returned),
  an empty recorded read returns ``b""``, a recorded error (e.g. an unplug) is raised again
  as the same exception class with the same message, after which the port stays dead.
* Writes must match the recorded TX byte-for-byte, in order; otherwise
  :class:`~labkit.errors.ReplayMismatch` names the port, the byte offset, the expected and
  the actual bytes with a caret under the first difference, and the driver call.
* Device bytes recorded after a write become readable only once that write has been
  replayed (a device cannot answer a command it has not seen); bytes recorded before it
  stay readable, so a stream reader and a command writer may interleave differently.
* ``mode=timed`` additionally makes each recorded read available at its recorded time
  (relative to the open) on the port's clock; on a virtual clock timeouts and settle loops
  replay deterministically and instantly. ``strict`` (the default) ignores times.
* Each ``open`` of the port replays the next recorded open/close session. Closing with
  unconsumed events raises ReplayMismatch; :meth:`ReplaySerial.assert_consumed` checks the
  whole cassette.
"""

from __future__ import annotations

import builtins
import threading
from typing import Any

import serial
from serial.serialutil import to_bytes

from labkit.errors import ReplayMismatch
from labkit.io.cassette import CassetteReader
from labkit.io.clocked import LINE_SETTINGS, REAL_POLL_S, VIRTUAL_POLL_S, ClockedSerial, poll_step
from labkit.io.replay_stream import DeviceItem, EventQueue, RecordedSession, is_open
from labkit.io.urls import parse_replay_url

__all__ = ["DeviceItem", "ReplaySerial", "mismatch_message", "rebuild_error", "render_bytes"]

#: recorded times are compared with this tolerance (float sums of clock offsets)
TIME_EPS = 1e-9


def rebuild_error(event: dict[str, Any]) -> BaseException:
    """The exception a recorded ``error`` event describes (same class and message)."""
    name, module = event.get("class", "SerialException"), event.get("module", "")
    message = event.get("message", "")
    cls: Any = None
    if module.startswith("serial"):
        cls = getattr(serial, name, None) or getattr(serial.serialutil, name, None)
    elif module == "builtins":
        cls = getattr(builtins, name, None)
    if not (isinstance(cls, type) and issubclass(cls, Exception)):
        cls = serial.SerialException
    try:
        exc = cls(message)
    except TypeError:  # e.g. PortNotOpenError() takes no message
        exc = cls()
    if isinstance(exc, OSError) and event.get("errno") is not None:
        exc.errno = event["errno"]
    return exc


def render_bytes(data: bytes) -> str:
    """Bytes as one escaped line where every byte has a fixed rendering (for caret alignment)."""
    out = []
    for b in data:
        if b == 0x0D:
            out.append("\\r")
        elif b == 0x0A:
            out.append("\\n")
        elif b == 0x5C:
            out.append("\\\\")
        elif 0x20 <= b < 0x7F:
            out.append(chr(b))
        else:
            out.append(f"\\x{b:02x}")
    return "".join(out)


def mismatch_message(port: str, cassette: str, session_offset: int, expected: bytes,
                     actual: bytes, column: int, call: str, line: int | None) -> str:
    """The strict-mode diff: both byte windows from a common start, a caret at ``column``.

    ``session_offset`` is the byte offset of the difference within the session's TX;
    ``column`` the same byte's index within the windows.
    """
    prefix = render_bytes(expected[:column])
    where = f" (cassette line {line})" if line else ""
    exp_text = render_bytes(expected) if len(expected) > column else render_bytes(expected) + "<end>"
    return (
        f"replay port {port!r} ({cassette}): TX differs at byte {session_offset} of the session, "
        f"call {call!r}{where}\n"
        f"  expected: {exp_text}\n"
        f"  actual:   {render_bytes(actual)}\n"
        f"            {' ' * len(prefix)}^"
    )


class ReplaySerial(ClockedSerial):
    """A port serving a cassette, read as the replay goes (:mod:`labkit.io.replay_stream`).
    ``port_name`` and the cassette's path are set at first open."""

    def __init__(self, *args, **kwargs) -> None:
        self.cassette_path = ""
        self.header: dict[str, Any] = {}
        self.mode = "strict"
        self.port_name = ""
        self._queue: EventQueue | None = None
        self._next_session = 0
        self._session: RecordedSession | None = None
        self._dead: dict[str, Any] | None = None
        self._chunk_pos = 0
        self._t0 = 0.0
        self._lock = threading.RLock()
        super().__init__(*args, **kwargs)

    # -- life cycle ---------------------------------------------------------------------
    def open(self) -> None:
        self._require_openable()
        clock = self._resolve_clock()
        if self._queue is None:
            spec = parse_replay_url(self.portstr)
            self.mode = spec.mode
            reader = CassetteReader(spec.cassette)
            self.cassette_path, self.header, self.port_name = str(reader.path), reader.header, reader.port
            self._queue = EventQueue(iter(reader))
        session = self._begin_session(self._queue)
        self._next_session += 1
        self._session = session
        self._dead = None
        self._chunk_pos = 0
        opened_t = session.open_event["t"] if session.open_event else 0.0
        self._t0 = clock.now() - opened_t
        self._check_settings(session)
        if session.open_error is not None:
            raise rebuild_error(session.open_error)
        self.is_open = True

    def _begin_session(self, queue: EventQueue) -> RecordedSession:
        """The next recorded session (the one before it read to its end)."""
        if self._session is not None:
            self._session.drain()
        first = queue.peek()
        if first is None or (self._next_session and not is_open(first)):
            raise ReplayMismatch(
                f"replay port {self.port_name!r} ({self._path()}): opened "
                f"{self._next_session + 1} times but the cassette recorded "
                f"{self._next_session} open(s)"
            )
        session = RecordedSession(queue, queue.pop() if is_open(first) else None)
        session.start()
        return session

    def _check_settings(self, session: RecordedSession) -> None:
        recorded = (session.open_event or {}).get("serial") or {}
        actual = self.settings_summary()
        for key in LINE_SETTINGS:
            if key in recorded and recorded[key] != actual[key]:
                raise ReplayMismatch(
                    f"replay port {self.port_name!r} ({self._path()}): opened with {key}="
                    f"{actual[key]!r} but the recording used {key}={recorded[key]!r}"
                )

    def _path(self) -> str:
        return self.cassette_path or self.portstr

    def close(self) -> None:
        was_open, self.is_open = self.is_open, False
        if was_open:
            problem = self._unconsumed()
            if problem:
                raise ReplayMismatch(problem)

    def _unconsumed(self) -> str:
        session = self._session
        if session is None or self._dead is not None:
            return ""  # after a recorded error only failures follow; a dead port replays them all
        left_tx, left_dev, first, left_err = session.drain()
        if not (left_tx or left_dev or left_err):
            return ""
        parts = []
        if left_tx:
            parts.append(f"{left_tx} TX bytes never written "
                         f"(next: {render_bytes(bytes(session.tx_pending[:24]))})")
        if left_dev and first is not None:
            what = render_bytes(first.data[self._chunk_pos:][:24]) if first.kind == "rx" else first.kind
            parts.append(f"{left_dev} recorded reads never made "
                         f"(next at cassette line {first.event.get('line')}: {what})")
        if left_err:
            parts.append(f"{left_err} recorded write errors never reached")
        return f"replay port {self.port_name!r} ({self._path()}): " + "; ".join(parts)

    def assert_consumed(self) -> None:
        """Raise ReplayMismatch unless every recorded session was opened and fully replayed."""
        with self._lock:
            problem = self._unconsumed()
            if problem:
                raise ReplayMismatch(problem)
            if self._session is not None:
                self._session.drain()
            left = self._count_opens_left()
            if left:
                raise ReplayMismatch(
                    f"replay port {self.port_name!r} ({self._path()}): the cassette recorded "
                    f"{self._next_session + left} open(s) but the port was opened "
                    f"{self._next_session} time(s)"
                )

    def _count_opens_left(self) -> int:
        """The recorded opens after the current session (the cassette read again from its start,
        kept nowhere; nothing to read when the replay is at its end)."""
        if self._queue is None or self._queue.peek() is None:
            return 0
        recorded, first = 0, True
        for event in CassetteReader(self.cassette_path):
            if is_open(event) or first:
                recorded += 1  # (events before any open are a session of their own)
            first = False
        return recorded - self._next_session

    # -- helpers ------------------------------------------------------------------------
    def _raise_if_dead(self) -> None:
        if self._dead is not None:
            raise rebuild_error(self._dead)

    def _die(self, event: dict[str, Any]) -> BaseException:
        self._dead = event
        return rebuild_error(event)

    def _current(self) -> DeviceItem | None:
        assert self._session is not None
        return self._session.next_device()

    def _delivered(self) -> None:
        assert self._session is not None
        self._session.device.popleft()
        self._chunk_pos = 0

    def _ready_at(self, item: DeviceItem) -> float | None:
        """Clock time from which ``item`` may be delivered; None while it awaits a write."""
        assert self._session is not None
        if self._session.tx_written < item.gate:
            return None
        return self._t0 + item.t if self.mode == "timed" else float("-inf")

    # -- traffic ------------------------------------------------------------------------
    def write(self, data: bytes) -> int:
        self._require_open()
        data = to_bytes(data)
        with self._lock:
            self._raise_if_dead()
            session = self._session
            assert session is not None
            expected = session.expected(len(data))
            pending = session.next_write_error()
            if pending and pending[0] == session.tx_written and not pending[1].get("tx_recorded"):
                session.write_errors.popleft()  # a write that failed before its bytes were recorded
                raise self._die(pending[1])
            if expected != data:
                self._raise_mismatch(data, expected)
            session.written(len(data))
            if pending and pending[0] == session.tx_written and pending[1].get("tx_recorded"):
                session.write_errors.popleft()  # these very bytes failed to go out
                raise self._die(pending[1])
        return len(data)

    def _raise_mismatch(self, data: bytes, expected: bytes) -> None:
        session = self._session
        assert session is not None
        diff = next((i for i, (a, b) in enumerate(zip(expected, data, strict=False)) if a != b),
                    min(len(expected), len(data)))
        written = session.tx_written
        offset = written + diff
        mark = session.mark_at(offset)
        start = max(mark[0], offset - 24, 0)
        before = session.tx_slice(start, written) if start < written else b""
        exp_window = session.tx_slice(start, offset + 16)
        act_window = (before + data)[:offset - start + 16]
        raise ReplayMismatch(mismatch_message(
            self.port_name, self._path(), offset, exp_window, act_window, offset - start,
            mark[1], mark[2],
        ))

    def read(self, size: int = 1) -> bytes:
        return self._read_chunk(size)

    def read_until(self, expected: bytes = b"\n", size: int | None = None) -> bytes:
        """One recorded read: the recorded ``read_until`` result (chunk-preserving)."""
        return self._read_chunk(size if size is not None else 1 << 30)

    def _read_chunk(self, size: int) -> bytes:
        self._require_open()
        if size <= 0:
            return b""
        clock = self._resolve_clock()
        deadline = None if self._timeout is None else clock.now() + self._timeout
        while True:
            with self._lock:
                self._raise_if_dead()
                now = clock.now()
                item = self._current()
                ready = self._ready_at(item) if item is not None else None
                if item is not None and ready is not None and ready <= now + TIME_EPS:
                    return self._deliver(item, size, clock)
                if self._timeout == 0 or (deadline is not None and now >= deadline):
                    return b""
            if item is None and deadline is None:
                raise ReplayMismatch(
                    f"replay port {self.port_name!r} ({self._path()}): a blocking read "
                    f"(timeout=None) after the last recorded read would wait forever"
                )
            self._wait(clock, now, ready, deadline)

    def _wait(self, clock, now: float, ready: float | None, deadline: float | None) -> None:
        if ready is not None:  # timed: sleep to the recorded time (or the timeout)
            target = ready if deadline is None or ready <= deadline + TIME_EPS else deadline
            clock.sleep_until(target)
        elif clock.is_virtual:
            if self._current() is None and deadline is not None:
                clock.sleep_until(deadline)  # nothing more recorded: a plain timeout
            else:  # awaiting a write that a clock job may make while we sleep
                clock.sleep(poll_step(VIRTUAL_POLL_S, now, deadline))
        else:
            clock.sleep(poll_step(REAL_POLL_S, now, deadline))

    def _deliver(self, item: DeviceItem, size: int, clock) -> bytes:
        if item.kind == "error":
            self._delivered()
            raise self._die(item.event)
        if item.kind == "empty":
            self._delivered()
            if self.mode == "strict" and clock.is_virtual and self._timeout:
                clock.sleep(self._timeout)  # a timed-out read took its timeout
            return b""
        out = item.data[self._chunk_pos:self._chunk_pos + size]
        self._chunk_pos += len(out)
        if self._chunk_pos >= len(item.data):
            self._delivered()
        return out

    @property
    def in_waiting(self) -> int:
        self._require_open()
        clock = self._resolve_clock()
        with self._lock:
            self._raise_if_dead()
            item = self._current()
            if item is None:
                return 0
            ready = self._ready_at(item)
            if ready is None or ready > clock.now() + TIME_EPS:
                return 0
            if item.kind == "error":
                self._delivered()
                raise self._die(item.event)
            return len(item.data) - self._chunk_pos if item.kind == "rx" else 0

    def reset_input_buffer(self) -> None:
        """Recorded reads only hold bytes that were read after a reset, so nothing to drop."""
        self._require_open()
        with self._lock:
            self._raise_if_dead()
