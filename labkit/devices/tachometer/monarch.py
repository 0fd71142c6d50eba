"""Monarch Instrument "@" command protocol
(docs/reference/devices-tach-motor.md#monarch_at-monarch--commands-act-1b-act-3x-f2a1x-tier-2): ACT-1B,
ACT-3X, F2A1X.

9600 8N1 through Monarch's USB programming cable. Commands are ``@`` + name + CR:
``@PI`` product and firmware (two lines), ``@D0`` the display value once, ``@D1``/``@D2``
start/stop continuous display data. Replies are data, ``OK`` or ``ERR``. The display value
changes at most twice a second (ACT-3X), so this is a slow tachometer; the exact number
format of the value lines was not documented in our sources [U]: the parser accepts a
signed decimal number optionally followed by ``RPM``, and nothing else.
"""

from __future__ import annotations

import re
from collections import deque
from typing import Any

from labkit.devices.link import ReplyQueue
from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.devices.tachometer.streaming import StreamingTachometer
from labkit.errors import DeviceReplyError, DeviceTimeout
from labkit.readings import Reading
from labkit.units import rpm_to_rad_s

VALUE_LINE = re.compile(rb"^\s*([+-]?\d{1,9}(?:\.\d{1,6})?)\s*(?:RPM|rpm)?\s*$")


def format_command(name: str) -> bytes:
    """``PI`` -> ``b"@PI\\r"``."""
    if not name or not name.isascii() or "\r" in name or "\n" in name:
        raise ValueError(f"bad Monarch command {name!r}")
    return b"@" + name.encode("ascii") + b"\r"


def parse_display_value(line: bytes) -> float:
    """A value line -> RPM (float). Raises ValueError for anything else."""
    match = VALUE_LINE.match(line)
    if not match:
        raise ValueError(f"not a display value: {line[:40]!r}")
    return float(match.group(1))


class EolFramer:
    """Lines ended by CR, LF or CR LF (the Monarch's line ends are not documented)."""

    def __init__(self, max_len: int = 128) -> None:
        self.buffer = bytearray()
        self.max_len = max_len
        self.dropped = 0

    def feed(self, data: bytes) -> list[bytes]:
        self.buffer += data
        lines: list[bytes] = []
        while True:
            ends = [i for i in (self.buffer.find(b"\r"), self.buffer.find(b"\n")) if i >= 0]
            if not ends:
                if len(self.buffer) > self.max_len:
                    self.buffer.clear()
                    self.dropped += 1
                return lines
            end = min(ends)
            line = bytes(self.buffer[:end])
            del self.buffer[:end + 1]
            if line and len(line) <= self.max_len:
                lines.append(line)


@register_driver
class MonarchTachometer(StreamingTachometer):
    """Monarch panel tachometer in continuous-display mode (``@D1``).

    Options: ``reply_timeout_s`` (1.0). On open: ``@D2`` (stop any stream: a known state),
    then ``@D1``; on close ``@D2``. Whether the meter answers ``@D1``/``@D2`` with ``OK`` is
    not documented [U], so the driver does not wait for it and skips ``OK`` lines.
    """

    protocol = "monarch_at"
    option_names = frozenset({"reply_timeout_s"})
    default_serial = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __init__(self, port: Any, clock: Any, name: str = "", **options: Any):
        self.reply_timeout_s = float(options.get("reply_timeout_s", 1.0))
        self._capture = 0
        self.replies = ReplyQueue(port, clock, name, check=self._check_reader,
                                  tail=lambda: self.reader.last_bytes, poll_s=0.005)
        self._replies = self.replies.replies
        super().__init__(port, clock, name, **options)
        self.send("D2")
        self.send("D1")

    def make_framer(self) -> EolFramer:
        return EolFramer()

    def parse_frame(self, t: float, frame: bytes) -> Reading | None:
        line = frame.strip()
        if self._capture > 0 and line not in (b"OK", b""):
            self._capture -= 1                 # an identification line, even if it looks numeric
            self.replies.put(line)
            return None
        try:
            rpm = parse_display_value(line)
        except ValueError:
            if line and all(32 <= b < 127 for b in line):
                self.replies.put(line)     # OK / ERR / identification text
                return None
            raise
        return Reading(t, "angular_speed", rpm_to_rad_s(rpm), "rad/s", raw=frame, device=self.name)

    def send(self, name: str) -> None:
        """Write ``@name`` without waiting for an answer (a dead port: DeviceDisconnected)."""
        self.replies.write(format_command(name), f"@{name}")

    def command(self, name: str, lines: int = 1) -> list[bytes]:
        """Send ``@name``; return its ``lines`` reply lines (``OK`` lines of earlier
        commands are skipped; value lines go to the reading buffer); ``ERR`` raises."""
        self._replies.clear()
        self.send(name)

        def ready(replies: deque[bytes]) -> bool:
            while replies and replies[0] == b"OK":
                replies.popleft()
            return len(replies) >= lines or bool(replies and replies[0] == b"ERR")

        if not self.replies.wait(ready, self.reply_timeout_s):
            got = len(self._replies)
            raise DeviceTimeout(self.name, f"@{name}", self.reader.last_bytes,
                                f"{got} of {lines} reply lines in {self.reply_timeout_s} s")
        if self._replies[0] == b"ERR":
            raise DeviceReplyError(self.name, f"@{name}", self.reader.last_bytes, "device answered ERR")
        return [self._replies.popleft() for _ in range(lines)]

    def identify(self) -> dict[str, Any]:
        """``@PI`` with the stream stopped (its two lines may look like values), then ``@D1``."""
        self.send("D2")
        self.clock.sleep(0.3)
        self._capture = 2
        try:
            product, firmware = self.command("PI", lines=2)
        finally:
            self._capture = 0
            self.send("D1")
        return {"model": product.decode("ascii", "replace"), "firmware": firmware.decode("ascii", "replace")}

    def close(self) -> None:
        try:
            self.send("D2")
        except Exception:  # noqa: BLE001 - closing a dead port must not raise
            pass
        super().close()


register_parser_benchmark("monarch_at", b"12345.6", parse_display_value)
