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
from dataclasses import dataclass, field
from typing import Any

import serial
from serial.serialutil import to_bytes

from labkit.errors import ReplayMismatch
from labkit.io.cassette import Cassette, load_cassette
from labkit.io.clocked import LINE_SETTINGS, REAL_POLL_S, VIRTUAL_POLL_S, ClockedSerial, poll_step
from labkit.io.urls import parse_replay_url

#: recorded times are compared with this tolerance (float sums of clock offsets)
TIME_EPS = 1e-9


@dataclass
class DeviceItem:
    """One thing the device side delivers: an ``rx`` chunk, an ``empty`` read or an ``error``."""

    kind: str
    t: float
    gate: int  # TX bytes of this session written before it was recorded
    event: dict[str, Any]
    data: bytes = b""


@dataclass
class PortSession:
    """Events between one ``open`` and the next."""

    open_event: dict[str, Any] | None = None
    open_error: dict[str, Any] | None = None
    tx: bytearray = field(default_factory=bytearray)
    tx_events: list[tuple[int, dict[str, Any]]] = field(default_factory=list)  # (offset, event)
    write_errors: list[tuple[int, dict[str, Any]]] = field(default_factory=list)  # (gate, event)
    device: list[DeviceItem] = field(default_factory=list)


def split_sessions(cassette: Cassette) -> list[PortSession]:
    """Group a cassette's events into open/close sessions, pairing reads with their markers."""
    sessions: list[PortSession] = []
    current: PortSession | None = None
    for event in cassette.events:
        kind = event.get("event") if event["dir"] == "ctl" else event["dir"]
        if kind == "open" or current is None:
            current = PortSession(open_event=event if kind == "open" else None)
            sessions.append(current)
            if kind == "open":
                continue
        gate = len(current.tx)
        if kind == "tx":
            current.tx_events.append((gate, event))
            current.tx += event["bytes"]
        elif kind == "rx":
            current.device.append(DeviceItem("rx", event["t"], gate, event, event["bytes"]))
        elif kind == "short_read":
            last = current.device[-1] if current.device else None
            attached = (last is not None and last.kind == "rx" and last.gate == gate
                        and event.get("got") == len(last.data) and "short" not in last.event)
            if attached and last is not None:
                last.event = {**last.event, "short": True}
            elif not event.get("got"):
                current.device.append(DeviceItem("empty", event["t"], gate, event))
        elif kind == "error":
            call = event.get("call", "")
            if call == "open":
                current.open_error = event
            elif call == "write":
                current.write_errors.append((gate, event))
            else:
                current.device.append(DeviceItem("error", event["t"], gate, event))
    return sessions


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
    """A port serving a cassette. ``port_name`` and ``cassette`` are set at first open."""

    def __init__(self, *args, **kwargs) -> None:
        self.cassette: Cassette | None = None
        self.mode = "strict"
        self.sessions: list[PortSession] = []
        self.port_name = ""
        self._next_session = 0
        self._session: PortSession | None = None
        self._tx_pos = 0
        self._dev_idx = 0
        self._chunk_pos = 0
        self._write_err_idx = 0
        self._dead: dict[str, Any] | None = None
        self._t0 = 0.0
        self._lock = threading.RLock()
        super().__init__(*args, **kwargs)

    # -- life cycle ---------------------------------------------------------------------
    def open(self) -> None:
        self._require_openable()
        clock = self._resolve_clock()
        if self.cassette is None:
            spec = parse_replay_url(self.portstr)
            self.mode = spec.mode
            self.cassette = load_cassette(spec.cassette)
            self.port_name = self.cassette.port
            self.sessions = split_sessions(self.cassette)
        if self._next_session >= len(self.sessions):
            raise ReplayMismatch(
                f"replay port {self.port_name!r} ({self.cassette.path}): opened "
                f"{self._next_session + 1} times but the cassette recorded "
                f"{len(self.sessions)} open(s)"
            )
        session = self.sessions[self._next_session]
        self._next_session += 1
        self._session = session
        self._tx_pos = self._dev_idx = self._chunk_pos = self._write_err_idx = 0
        self._dead = None
        opened_t = session.open_event["t"] if session.open_event else 0.0
        self._t0 = clock.now() - opened_t
        self._check_settings(session)
        if session.open_error is not None:
            raise rebuild_error(session.open_error)
        self.is_open = True

    def _check_settings(self, session: PortSession) -> None:
        recorded = (session.open_event or {}).get("serial") or {}
        actual = self.settings_summary()
        for key in LINE_SETTINGS:
            if key in recorded and recorded[key] != actual[key]:
                raise ReplayMismatch(
                    f"replay port {self.port_name!r} ({self._path()}): opened with {key}="
                    f"{actual[key]!r} but the recording used {key}={recorded[key]!r}"
                )

    def _path(self) -> str:
        return str(self.cassette.path) if self.cassette else self.portstr

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
        left_tx = len(session.tx) - self._tx_pos
        left_dev = session.device[self._dev_idx:]
        left_err = session.write_errors[self._write_err_idx:]
        if not (left_tx or left_dev or left_err):
            return ""
        parts = []
        if left_tx:
            parts.append(f"{left_tx} TX bytes never written "
                         f"(next: {render_bytes(bytes(session.tx[self._tx_pos:self._tx_pos + 24]))})")
        if left_dev:
            first = left_dev[0]
            what = render_bytes(first.data[self._chunk_pos:][:24]) if first.kind == "rx" else first.kind
            parts.append(f"{len(left_dev)} recorded reads never made "
                         f"(next at cassette line {first.event.get('line')}: {what})")
        if left_err:
            parts.append(f"{len(left_err)} recorded write errors never reached")
        return f"replay port {self.port_name!r} ({self._path()}): " + "; ".join(parts)

    def assert_consumed(self) -> None:
        """Raise ReplayMismatch unless every recorded session was opened and fully replayed."""
        with self._lock:
            problem = self._unconsumed()
            if problem:
                raise ReplayMismatch(problem)
            if self._next_session < len(self.sessions):
                raise ReplayMismatch(
                    f"replay port {self.port_name!r} ({self._path()}): the cassette recorded "
                    f"{len(self.sessions)} open(s) but the port was opened {self._next_session} time(s)"
                )

    # -- helpers ------------------------------------------------------------------------
    def _raise_if_dead(self) -> None:
        if self._dead is not None:
            raise rebuild_error(self._dead)

    def _die(self, event: dict[str, Any]) -> BaseException:
        self._dead = event
        return rebuild_error(event)

    def _current(self) -> DeviceItem | None:
        assert self._session is not None
        device = self._session.device
        return device[self._dev_idx] if self._dev_idx < len(device) else None

    def _ready_at(self, item: DeviceItem) -> float | None:
        """Clock time from which ``item`` may be delivered; None while it awaits a write."""
        if self._tx_pos < item.gate:
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
            errors = session.write_errors
            pending = errors[self._write_err_idx] if self._write_err_idx < len(errors) else None
            if pending and pending[0] == self._tx_pos and not pending[1].get("tx_recorded"):
                self._write_err_idx += 1  # a write that failed before its bytes were recorded
                raise self._die(pending[1])
            expected = bytes(session.tx[self._tx_pos:self._tx_pos + len(data)])
            if expected != data:
                self._raise_mismatch(data, expected)
            self._tx_pos += len(data)
            if pending and pending[0] == self._tx_pos and pending[1].get("tx_recorded"):
                self._write_err_idx += 1  # these very bytes failed to go out
                raise self._die(pending[1])
        return len(data)

    def _raise_mismatch(self, data: bytes, expected: bytes) -> None:
        session = self._session
        assert session is not None
        diff = next((i for i, (a, b) in enumerate(zip(expected, data, strict=False)) if a != b),
                    min(len(expected), len(data)))
        offset = self._tx_pos + diff
        start_event = max((e for e in session.tx_events if e[0] <= offset),
                          key=lambda e: e[0], default=(0, {}))
        start = max(start_event[0], offset - 24, 0)
        before = bytes(session.tx[start:self._tx_pos])
        exp_window = bytes(session.tx[start:offset + 16])
        act_window = (before + data)[:offset - start + 16]
        raise ReplayMismatch(mismatch_message(
            self.port_name, self._path(), offset, exp_window, act_window, offset - start,
            start_event[1].get("call", "write"), start_event[1].get("line"),
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
            self._dev_idx += 1
            raise self._die(item.event)
        if item.kind == "empty":
            self._dev_idx += 1
            if self.mode == "strict" and clock.is_virtual and self._timeout:
                clock.sleep(self._timeout)  # a timed-out read took its timeout
            return b""
        out = item.data[self._chunk_pos:self._chunk_pos + size]
        self._chunk_pos += len(out)
        if self._chunk_pos >= len(item.data):
            self._dev_idx += 1
            self._chunk_pos = 0
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
                self._dev_idx += 1
                raise self._die(item.event)
            return len(item.data) - self._chunk_pos if item.kind == "rx" else 0

    def reset_input_buffer(self) -> None:
        """Recorded reads only hold bytes that were read after a reset, so nothing to drop."""
        self._require_open()
        with self._lock:
            self._raise_if_dead()
