"""Driver of the labkit stroboscope locked to the rotor (``firmware/labkit_strobe``,
docs/reference/devices-strobe.md): device kind ``strobe``, protocol ``labkit_strobe``.

The strobe talks on its own (a status line every 1/RATE s): one
:class:`~labkit.devices.stream_reader.StreamReader` cuts lines, status lines go into a buffer that
``latest()``, ``statuses_since(t)`` and ``wait_status(timeout)`` read, replies (``OK``,
``ERR ..``, ``ID ..``) to the command waiting for them. On open (which resets an Arduino)
the driver waits for the banner or a status line, then sends its settings; after a reset
(a new banner) it sends them again and the next status carries the flag ``reset``.
"""

from __future__ import annotations

import threading
from abc import abstractmethod
from typing import Any

import serial

from labkit.devices.base import Device
from labkit.devices.link import LineFramer, ReplyQueue
from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.devices.sketch_commands import SketchCommands, is_reply
from labkit.devices.stream_reader import StreamReader
from labkit.devices.strobe.protocol import (
    StrobeStatus,
    format_command,
    parse_banner,
    parse_status_line,
    strip_junk,
)
from labkit.errors import DeviceTimeout
from labkit.io.clock import Clock


class Strobe(Device):
    """A stroboscope flashing at a commanded offset from the rotor (device kind ``strobe``)."""

    kind = "strobe"

    @abstractmethod
    def set_offset(self, offset_hz: float) -> None:
        """The apparent frequency the flashes show, Hz (the strobe runs at (f_rot - offset)/m)."""

    @abstractmethod
    def set_width(self, width_us: float) -> None:
        """The flash length, us."""

    @abstractmethod
    def set_divider(self, divider: int) -> None:
        """Flash every ``divider``-th revolution."""

    @abstractmethod
    def lamp(self, on: bool) -> None:
        """Switch the flashes on or off."""

    @abstractmethod
    def latest(self) -> StrobeStatus | None:
        """The newest status, or None before the first."""

    @abstractmethod
    def statuses_since(self, t: float) -> list[StrobeStatus]:
        """All statuses received at clock time > t, oldest first."""

    def wait_status(self, timeout: float = 3.0) -> StrobeStatus:
        """Block (on the clock) until a status newer than now arrives."""
        start = self.clock.now()
        while True:
            new = self.statuses_since(start)
            if new:
                return new[-1]
            if self.clock.now() - start >= timeout:
                raise DeviceTimeout(self.name, "status", self.last_bytes, f"no status line in {timeout} s")
            self.clock.sleep(0.01)


@register_driver
class LabkitStrobe(SketchCommands, Strobe):
    """Options (all sent on open): ``offset_hz`` (0.5), ``width_us`` (20), ``divider`` (1),
    ``rate_hz`` (status lines per second, 1), ``lamp`` (True); ``boot_timeout_s`` (3: opening
    an Arduino's port resets it), ``reply_timeout_s`` (0.5)."""

    protocol = "labkit_strobe"
    #: its status lines come unasked: a faithful replay serves them at their recorded times and
    #: holds a command's reply until the replayed command was sent (labkit.protocols.replay)
    talks_unasked = True
    option_names = frozenset({"boot_timeout_s", "divider", "lamp", "offset_hz", "rate_hz",
                              "reply_timeout_s", "width_us"})
    default_serial = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}
    history = 20_000
    reader_period = 0.005

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        self.settings: dict[str, float] = {
            "OFFSET": float(options.get("offset_hz", 0.5)), "WIDTH": float(options.get("width_us", 20)),
            "DIV": float(options.get("divider", 1)), "RATE": float(options.get("rate_hz", 1))}
        for command, value in self.settings.items():
            format_command(command, value)          # a bad option fails here, before any I/O
        self.lamp_on = str(options.get("lamp", True)).lower() not in ("0", "false", "no", "off")
        self.reply_timeout_s = float(options.get("reply_timeout_s", 0.5))
        self.banner: dict[str, str] = {}
        self.resets = 0
        self.lines_lost = 0
        self.frames_rejected = 0
        self._lock = threading.Lock()
        self._statuses: list[StrobeStatus] = []
        self._alive = False
        self._flag_reset = False
        self._last_seq: int | None = None
        self.reader = StreamReader(port, clock, LineFramer(b"\n", max_len=128), self._on_frame,
                                   device=self.name, period=self.reader_period)
        self.replies = ReplyQueue(port, clock, self.name, check=self._check_reader,
                                  tail=lambda: self.reader.last_bytes)
        try:
            port.reset_input_buffer()
        except (serial.SerialException, OSError, AttributeError):
            pass
        self.reader.start()
        try:
            self._wait_alive(float(options.get("boot_timeout_s", 3.0)), "status line")
            self._configure()
        except Exception:
            self.close()
            raise

    # ---- frames -------------------------------------------------------------------------
    def _on_frame(self, t: float, frame: bytes) -> None:
        line = strip_junk(frame.strip())
        if not line:
            return
        if line.startswith(b"#"):
            self._on_banner(line)
        elif is_reply(line):
            self.replies.put(line)
        else:
            try:
                status = parse_status_line(line, t, self.name, int(self.settings["DIV"]))
            except ValueError:
                self.frames_rejected += 1
                return
            self._add(status)

    def _on_banner(self, line: bytes) -> None:
        banner = parse_banner(line)
        if banner is not None:
            self._note_banner(banner, self._lock)

    def _add(self, status: StrobeStatus) -> None:
        with self._lock:
            self._alive = True
            if self._last_seq is not None and status.seq > self._last_seq + 1:
                self.lines_lost += status.seq - self._last_seq - 1
            self._last_seq = status.seq
            if self._flag_reset:
                self._flag_reset = False
                status = StrobeStatus(**{**status.__dict__, "flags": status.flags | {"reset"}})
            self._statuses.append(status)
            if len(self._statuses) > self.history:
                del self._statuses[: self.history // 10]

    def _check_reader(self) -> None:
        self.last_bytes = self.reader.last_bytes
        self.reader.check()

    def latest(self) -> StrobeStatus | None:
        self._check_reader()
        with self._lock:
            return self._statuses[-1] if self._statuses else None

    def statuses_since(self, t: float) -> list[StrobeStatus]:
        self._check_reader()
        with self._lock:
            return [s for s in self._statuses if s.t > t]

    # ---- commands -----------------------------------------------------------------------
    def command(self, name: str, value: float | None = None) -> bytes:
        """Send one command, return its reply line (``OK``/``ID ...``); ``ERR`` raises."""
        data = format_command(name, value)
        return self._exchange(data, data.decode().strip())

    def _config_commands(self) -> list[tuple[str, float | None]]:
        out: list[tuple[str, float | None]] = list(self.settings.items())
        out.append(("ON" if self.lamp_on else "OFF", None))
        return out

    def _configure(self) -> None:
        for name, value in self._config_commands():
            self.command(name, value)

    def _resend_config(self) -> None:
        """After a device reset (called by the reader): send the settings without waiting."""
        try:
            with self.replies.write_lock:
                for name, value in self._config_commands():
                    self.port.write(format_command(name, value))
        except Exception:  # noqa: BLE001 - a dead port is reported by the reader itself
            pass

    def set_offset(self, offset_hz: float) -> None:
        self.command("OFFSET", offset_hz)
        self.settings["OFFSET"] = float(offset_hz)

    def set_width(self, width_us: float) -> None:
        self.command("WIDTH", width_us)
        self.settings["WIDTH"] = float(width_us)

    def set_divider(self, divider: int) -> None:
        self.command("DIV", divider)
        self.settings["DIV"] = float(divider)

    def lamp(self, on: bool) -> None:
        self.command("ON" if on else "OFF")
        self.lamp_on = on

    def identify(self) -> dict[str, Any]:
        reply = self.command("ID?").decode("ascii", "replace").split()
        return {"model": reply[1] if len(reply) > 1 else "", "firmware": reply[2] if len(reply) > 2 else "",
                "offset_hz": self.settings["OFFSET"], "width_us": self.settings["WIDTH"],
                "divider": int(self.settings["DIV"]), "lamp": self.lamp_on}

    def close(self) -> None:
        self.reader.stop()
        super().close()


SAMPLE_LINE = b"S,1234,1234001,1000.0000,999.5000,123.4,0"
register_parser_benchmark("labkit_strobe", SAMPLE_LINE, parse_status_line)
