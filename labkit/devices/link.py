"""The one transport layer between a serial port and the drivers (issue 12, docs/explanation/developing.md).

Disconnect, timeout and resync are handled here once, with the messages drivers have always
given (tests/devices pins them):

* :class:`LineLink` - request/reply over text lines (the balances: MT-SICS, A&D, HX711
  sketches). Every read has a timeout on the injected :class:`~labkit.io.clock.Clock` (never
  ``time.sleep``), garbage is dropped up to the next terminator, a partial line left over from
  before a command is discarded, an unplugged port is detected by real I/O (``in_waiting`` is
  an ioctl that fails on a dead adapter; ``is_open`` is not trusted), and a timeout with only
  garbage says "check baud rate/parity".
* :class:`PacketLink` - whole binary packets (the motor controllers: VESC, Pololu SMC): one
  locked write per packet, exact-length reads with a deadline, a quiet check for garbled
  replies.
* :class:`ReplyQueue` - commands to a device that streams on its own (the tachometers): a
  background :class:`~labkit.devices.stream_reader.StreamReader` owns the input and hands reply
  lines here; the caller waits for them on the clock.
* :class:`ReadingBuffer` - the one buffer of a streaming device's readings.
* :class:`LineFramer` - bytes cut into frames at a terminator, for a link and for a
  :class:`~labkit.devices.stream_reader.StreamReader` alike (the Lutron and VESC framers live
  with their drivers; :class:`Framer` is what each provides).
"""

from __future__ import annotations

import bisect
import threading
from collections import deque
from collections.abc import Callable
from typing import Any, Protocol, TypeVar

import serial

from labkit.errors import DeviceDisconnected, DeviceError, DeviceTimeout
from labkit.io.calls import port_call, read_time
from labkit.io.clock import Clock
from labkit.readings import Reading

try:  # a hung-up pty raises termios.error (not an OSError) from tcflush
    from termios import error as _TermiosError
except ImportError:  # pragma: no cover - Windows
    _TermiosError = OSError  # type: ignore[assignment,misc]

__all__ = [
    "PORT_ERRORS", "FrameError", "Framer", "LineFramer", "LineLink", "LinkTailMixin", "PacketLink",
    "ReadingBuffer", "ReplyQueue", "describe_serial", "eol_bytes", "port_settings",
]

T = TypeVar("T")

#: what a dead port raises
PORT_ERRORS = (serial.SerialException, OSError, _TermiosError)


class FrameError(ValueError):
    """A line is not a valid frame of the protocol (garbage, partial, wrong baud)."""


def describe_serial(settings: dict[str, Any]) -> str:
    """``{"baudrate": 2400, "bytesize": 7, "parity": "E", "stopbits": 1}`` -> ``"2400 7E1"``."""
    baud = settings.get("baudrate", 9600)
    bits = settings.get("bytesize", 8)
    parity = str(settings.get("parity", "N"))[:1].upper()
    stop = settings.get("stopbits", 1)
    stop_text = f"{stop:g}" if isinstance(stop, float) else str(stop)
    return f"{baud} {bits}{parity}{stop_text}"


def port_settings(port: serial.SerialBase) -> dict[str, Any]:
    """The serial settings a port is open with (works for any ``SerialBase``)."""
    return {
        "baudrate": getattr(port, "baudrate", None),
        "bytesize": getattr(port, "bytesize", None),
        "parity": getattr(port, "parity", None),
        "stopbits": getattr(port, "stopbits", None),
    }


class LinkTailMixin:
    """For drivers that talk through a :class:`LineLink` kept as ``self.link``: their
    ``last_bytes`` (for error messages) is the link's tail, before the link exists ``b""``.
    Setting it is ignored (the base driver's ``__init__`` sets it; the link keeps the tail).
    """

    @property
    def last_bytes(self) -> bytes:
        link = getattr(self, "link", None)
        return link.last_bytes if link is not None else b""

    @last_bytes.setter
    def last_bytes(self, value: bytes) -> None:
        pass


class Framer(Protocol):
    """Turns the bytes read so far into whole frames (:class:`LineFramer`, the Lutron and VESC
    framers)."""

    def feed(self, data: bytes) -> list[bytes]: ...


class LineFramer:
    """Cuts a byte stream at a terminator (default LF; CR-only devices pass ``b"\\r"``).

    Lines are returned without the terminator and with a trailing CR stripped. A line
    longer than ``max_len`` is dropped (garbage, or wrong baud) and counted.
    """

    def __init__(self, terminator: bytes = b"\n", max_len: int = 256) -> None:
        self.terminator = terminator
        self.max_len = max_len
        self.buffer = bytearray()
        self.dropped = 0

    def feed(self, data: bytes) -> list[bytes]:
        self.buffer += data
        lines: list[bytes] = []
        while True:
            idx = self.buffer.find(self.terminator)
            if idx < 0:
                if len(self.buffer) > self.max_len:
                    self.buffer.clear()
                    self.dropped += 1
                return lines
            line = bytes(self.buffer[:idx])
            del self.buffer[: idx + len(self.terminator)]
            if len(line) > self.max_len:
                self.dropped += 1
                continue
            lines.append(line.rstrip(b"\r"))


def eol_bytes(eol: str) -> bytes:
    """Rig-file spelling of a line end (``"CRLF"``, ``"CR"``, ``"LF"``) -> bytes."""
    table = {"CRLF": b"\r\n", "CR": b"\r", "LF": b"\n"}
    try:
        return table[eol.upper()]
    except KeyError:
        raise ValueError(f"eol {eol!r}: expected one of CRLF, CR, LF") from None


class LineLink:
    """Send commands and collect reply lines with timeouts, resync and clear errors.

    ``accept(line)`` (the driver's) returns the parsed reply, ``None`` for a valid line
    that is not the reply (unsolicited output, handed to ``on_unsolicited``), raises
    :class:`FrameError` for garbage, or raises a :class:`~labkit.errors.DeviceError` for
    an error reply. ``single_bytes`` are bytes that are frames on their own (A&D ACK 0x06).
    """

    def __init__(
        self,
        port: serial.SerialBase,
        clock: Clock,
        device: str,
        *,
        expected_serial: dict[str, Any],
        write_eol: bytes = b"\r\n",
        read_eol: bytes = b"\n",
        single_bytes: bytes = b"",
        poll_s: float = 0.005,
        on_unsolicited: Callable[[float, bytes], None] | None = None,
    ) -> None:
        self.port = port
        self.clock = clock
        self.device = device
        self.expected_serial = expected_serial
        self.write_eol = write_eol
        self.framer = LineFramer(terminator=read_eol, max_len=256)
        self.single_bytes = single_bytes
        self.poll_s = poll_s
        self.on_unsolicited = on_unsolicited
        self.lines: deque[tuple[float, bytes]] = deque()
        self.tail = bytearray()  # last bytes received, for error messages
        self.bytes_received = 0
        self.garbage_lines = 0

    # ---- raw I/O ----------------------------------------------------------------------
    @property
    def last_bytes(self) -> bytes:
        return bytes(self.tail[-64:])

    def _disconnected(self, command: str, exc: BaseException) -> DeviceDisconnected:
        return DeviceDisconnected(self.device, command, self.last_bytes, f"port disconnected ({exc})")

    def pull(self, command: str = "read") -> int:
        """Move what the port has now into complete lines (never waits). Returns bytes read."""
        try:
            waiting = self.port.in_waiting
            data = self.port.read(waiting) if waiting else b""
        except (serial.SerialException, OSError) as exc:
            raise self._disconnected(command, exc) from exc
        if not data:
            return 0
        t = read_time(self.port, self.clock)
        self.bytes_received += len(data)
        self.tail += data
        del self.tail[:-256]
        for line in self._frame(data):
            self.lines.append((t, line))
        return len(data)

    def _frame(self, data: bytes) -> list[bytes]:
        if not self.single_bytes:
            return self.framer.feed(data)
        out: list[bytes] = []
        start = 0
        for i, byte in enumerate(data):
            if byte in self.single_bytes:
                out.extend(self.framer.feed(data[start:i]))
                out.append(bytes([byte]))
                start = i + 1
        out.extend(self.framer.feed(data[start:]))
        return out

    def send(self, command: str) -> None:
        """Write ``command`` + line end in one write (A&D E03: no slow command bytes)."""
        try:
            self.port.write(command.encode("ascii") + self.write_eol)
        except (serial.SerialException, OSError) as exc:
            raise self._disconnected(command, exc) from exc

    def discard_stale(self, command: str = "read") -> None:
        """Before a command: pull what is waiting, hand complete lines to ``on_unsolicited``
        and drop the partial line (so junk from before cannot corrupt the reply)."""
        self.pull(command)
        while self.lines:
            t, line = self.lines.popleft()
            if line and self.on_unsolicited is not None:
                self.on_unsolicited(t, line)
        self.framer.buffer.clear()

    # ---- request / response -----------------------------------------------------------
    def exchange(
        self,
        command: str | None,
        accept: Callable[[bytes], T | None],
        timeout: float,
        retry_after: float | None = None,
    ) -> tuple[float, bytes, T]:
        """Send ``command`` (None: just listen) and return ``(t, line, accept(line))`` for
        the first line ``accept`` takes. Resends after ``retry_after`` s without a reply.

        Raises :class:`~labkit.errors.DeviceTimeout` after ``timeout`` s; when only garbage
        arrived the message says to check baud rate/parity.
        """
        label = command if command is not None else "listen"
        with port_call(label):
            return self._exchange(label, command, accept, timeout, retry_after)

    def _exchange(self, label: str, command: str | None, accept: Callable[[bytes], T | None],
                  timeout: float, retry_after: float | None) -> tuple[float, bytes, T]:
        if command is not None:
            self.discard_stale(label)
            self.send(command)
        start = self.clock.now()
        deadline = start + timeout
        resend_at = start + retry_after if (retry_after and command is not None) else None
        received_at_start = self.bytes_received
        garbage = 0
        valid = 0
        while True:
            self.pull(label)
            while self.lines:
                t, line = self.lines.popleft()
                if not line:
                    continue
                try:
                    result = accept(line)
                except FrameError:
                    garbage += 1
                    self.garbage_lines += 1
                    continue
                valid += 1
                if result is None:
                    if self.on_unsolicited is not None:
                        self.on_unsolicited(t, line)
                    continue
                return t, line, result
            now = self.clock.now()
            if now >= deadline:
                raise self._timeout(label, timeout, garbage, valid, received_at_start)
            if resend_at is not None and now >= resend_at and command is not None:
                self.framer.buffer.clear()
                self.send(command)
                resend_at = now + (retry_after or timeout)
            self.clock.sleep(self.poll_s)

    def _timeout(self, command: str, timeout: float, garbage: int, valid: int,
                 received_at_start: int) -> DeviceTimeout:
        expected = describe_serial(self.expected_serial)
        actual_settings = port_settings(self.port)
        settings = f"expected {expected}"
        if actual_settings.get("baudrate") is not None:
            actual = describe_serial(actual_settings)
            if actual != expected:
                settings += f", port is {actual}"
        got_bytes = self.bytes_received - received_at_start
        if valid == 0 and (garbage or self.framer.buffer or self.framer.dropped) and got_bytes:
            reason = f"no valid reply in {timeout:g} s, only garbage; check baud rate/parity ({settings})"
        elif got_bytes == 0:
            reason = (f"no reply in {timeout:g} s; check the cable, the port and that the device "
                      f"is on and set to {expected}")
        else:
            reason = f"no reply to {command!r} in {timeout:g} s"
        return DeviceTimeout(self.device, command, self.last_bytes, reason)


class PacketLink:
    """Whole binary packets to and from one port (the motor controllers).

    ``write`` is locked per packet only (not across a query's wait, which the driver's own
    ``io_lock`` covers), so a keep-alive thread is never held up by a slow status read. Every
    port error becomes :class:`~labkit.errors.DeviceDisconnected` naming the command.
    """

    def __init__(self, port: serial.SerialBase, clock: Clock, device: str, poll_s: float = 0.001) -> None:
        self.port = port
        self.clock = clock
        self.device = device
        self.poll_s = poll_s
        self.last_bytes = b""  # tail of what was received, for error messages
        self._write_lock = threading.Lock()

    def write(self, data: bytes, command: str) -> None:
        """Write one whole packet; a dead port becomes DeviceDisconnected naming the command."""
        with self._write_lock:
            try:
                self.port.write(data)
            except PORT_ERRORS as exc:
                raise DeviceDisconnected(self.device, command, self.last_bytes, str(exc)) from exc

    def read_available(self, command: str) -> bytes:
        """What the port has now (never waits)."""
        try:
            waiting = self.port.in_waiting
            data = self.port.read(waiting) if waiting else b""
        except PORT_ERRORS as exc:
            raise DeviceDisconnected(self.device, command, self.last_bytes, str(exc)) from exc
        if data:
            self.last_bytes = (self.last_bytes + data)[-64:]
        return data

    def flush_input(self, command: str) -> None:
        """Drop what is waiting (resync before a query)."""
        try:
            self.port.reset_input_buffer()
        except PORT_ERRORS as exc:
            raise DeviceDisconnected(self.device, command, self.last_bytes, str(exc)) from exc

    def read_exact(self, n: int, timeout: float, command: str, quiet_s: float = 0.0) -> bytes:
        """Read exactly ``n`` bytes within ``timeout`` (clock time), polling the port.

        With ``quiet_s`` > 0 the line must then stay silent that long: extra bytes mean the
        reply was garbled (junk before/after it) and raise DeviceError.
        """
        deadline = self.clock.now() + timeout
        got = bytearray()
        while len(got) < n:
            got += self.read_available(command)
            if len(got) >= n:
                break
            if self.clock.now() >= deadline:
                raise DeviceTimeout(self.device, command, bytes(got) or self.last_bytes,
                                    f"{len(got)} of {n} reply bytes in {timeout} s")
            self.clock.sleep(self.poll_s)
        if quiet_s > 0:
            self.clock.sleep(quiet_s)
            got += self.read_available(command)
        if len(got) != n:
            raise DeviceError(self.device, command, bytes(got),
                              f"garbled reply: {len(got)} bytes where {n} were expected")
        return bytes(got)


class ReplyQueue:
    """Commands to a device that also talks on its own (a streaming tachometer).

    The device's :class:`~labkit.devices.stream_reader.StreamReader` owns the input: its frame parser
    hands reply lines to :meth:`put`. :meth:`write` sends a command (a dead port:
    DeviceDisconnected naming it); :meth:`wait` polls the reader (which raises what it hit,
    e.g. an unplug) until ``ready(replies)`` or the clock deadline, and says if it timed out.
    """

    def __init__(self, port: serial.SerialBase, clock: Clock, device: str,
                 check: Callable[[], None], tail: Callable[[], bytes], poll_s: float = 0.002) -> None:
        self.port = port
        self.clock = clock
        self.device = device
        self.check = check
        self.tail = tail
        self.poll_s = poll_s
        self.replies: deque[bytes] = deque()
        self.write_lock = threading.Lock()

    def put(self, line: bytes) -> None:
        self.replies.append(line)

    def write(self, data: bytes, command: str) -> None:
        """Write to the device; a dead port becomes DeviceDisconnected naming the command."""
        try:
            with self.write_lock:
                self.port.write(data)
        except (serial.SerialException, OSError) as exc:
            raise DeviceDisconnected(self.device, command, self.tail(), str(exc)) from exc

    def wait(self, ready: Callable[[deque[bytes]], bool], timeout: float) -> bool:
        """Poll until ``ready(self.replies)``; False when ``timeout`` s of clock time passed."""
        deadline = self.clock.now() + timeout
        while not ready(self.replies):
            self.check()
            if self.clock.now() >= deadline:
                return False
            self.clock.sleep(self.poll_s)
        return True


class ReadingBuffer:
    """The newest ``history`` readings of one device, oldest first.

    Readings are added by one reader (a thread on a real clock, a clock job on a virtual one)
    in clock order; any thread may read. When full, the oldest tenth is dropped at once (so
    adding stays cheap): the buffer then holds between 0.9 and 1.0 times ``history``.
    """

    def __init__(self, history: int, before_read: Callable[[], None] | None = None) -> None:
        if history < 1:
            raise ValueError(f"history {history}: must be >= 1")
        self.history = history
        #: called before every read (the device's reader raises what it hit, e.g. an unplug)
        self.before_read = before_read
        self._times: list[float] = []
        self._readings: list[Reading] = []
        self._lock = threading.Lock()

    def add(self, reading: Reading) -> None:
        with self._lock:
            self._times.append(reading.t)
            self._readings.append(reading)
            if len(self._readings) > self.history:
                drop = len(self._readings) - self.history + self.history // 10
                del self._times[:drop]
                del self._readings[:drop]

    def latest(self) -> Reading | None:
        """The newest reading, or None before the first."""
        if self.before_read is not None:
            self.before_read()
        with self._lock:
            return self._readings[-1] if self._readings else None

    def since(self, t: float) -> list[Reading]:
        """The readings received at clock time > ``t``, oldest first."""
        if self.before_read is not None:
            self.before_read()
        with self._lock:
            return self._readings[bisect.bisect_right(self._times, t):]

    def __len__(self) -> int:
        with self._lock:
            return len(self._readings)
