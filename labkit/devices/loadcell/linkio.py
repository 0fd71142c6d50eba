"""Line-based request/response over an open serial port, on the injected clock.

Shared by the balance drivers (MT-SICS, A&D, HX711 line sketches). It owns the rules of
PROTOCOLS 5.3: every read has a timeout measured on the :class:`~labkit.io.clock.Clock`
(never ``time.sleep``), garbage is dropped up to the next terminator, a partial line left
over from before a command is discarded, a port that went away is detected by real I/O
(``in_waiting`` is an ioctl that fails on an unplugged adapter, ``is_open`` is not
trusted), and a timeout with nothing but garbage says "check baud rate/parity".
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Any, TypeVar

import serial

from labkit.devices.stream import LineFramer
from labkit.errors import DeviceDisconnected, DeviceTimeout
from labkit.io.calls import port_call
from labkit.io.clock import Clock

T = TypeVar("T")


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
        t = self.clock.now()
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
