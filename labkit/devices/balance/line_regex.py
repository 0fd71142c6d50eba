"""Configurable line reader for third-party HX711 + Arduino sketches
(docs/reference/devices-balance.md#line_regex-hx711--arduino-sketches).

There is no HX711 serial standard: each sketch prints its own lines. A *preset* names a
known sketch (its line pattern, baud rate and tare command); any option can be overridden
in the rig file. A line pattern is a regular expression with a named group ``value``
(and optionally ``unit``); lines that do not match (boot banners, ``Tare complete``) are
skipped, never read as numbers. Values become SI with ``(value - offset) * scale`` in
``unit`` (``g``, ``kg``, ``N``... or ``raw`` for uncalibrated ADC counts).

The sketches stream continuously; the driver reads the next line that arrives after the
call.

Overload: the HX711 saturates at its rails, 0x7FFFFF / -0x800000 counts (datasheet); the
public sketches of the presets print no overload marker of their own. A printed rail code
is overload whatever the calibration; a calibrated sketch prints a constant number beyond
the cell's range instead, which only ``capacity`` (the cell's rated load, in the printed
unit) can catch. Overload readings have value NaN, ``overload=True``, ``stable=False``.

Reset: an Arduino that reboots (brown-out, watchdog, USB re-enumeration) prints its boot
banner again and tares itself at start-up with whatever load is on the cell. Banner lines
(``boot_pattern``, per preset) are never read as weights; one that follows a value line
counts as a device reset (``resets_seen``) and the next reading carries the flags
``device_reset`` and ``tare_lost``: its zero is the load at the reboot, not the user's.

The sketches report no stability: a reading is flagged stable only when ``stable_std`` is
set and the last ``stable_window`` values spread less than it; otherwise stable is True
with the flag ``stability_unknown``.
"""

from __future__ import annotations

import math
import re
import statistics
from collections import deque
from dataclasses import dataclass
from typing import Any

import serial

from labkit.devices.balance.continuous import ContinuousMixin
from labkit.devices.base import Balance
from labkit.devices.link import FrameError, LineLink, LinkTailMixin, eol_bytes
from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.errors import DeviceError, DeviceReplyError
from labkit.io.clock import Clock
from labkit.readings import Reading
from labkit.units import UnitError, to_si

FLOAT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d{1,3})?"

#: HX711 24-bit two's complement saturation codes
#: (docs/reference/devices-balance.md#line_regex-hx711--arduino-sketches)
HX711_MAX = 0x7FFFFF
HX711_MIN = -0x800000


@dataclass(frozen=True)
class Preset:
    """A known sketch: how its lines look, its baud rate and how it tares."""

    pattern: str
    baudrate: int
    unit: str = "g"
    tare_command: str | None = "t"   # None: the sketch reads no serial input, cannot tare
    tare_reply: str | None = None   # regex of the line confirming a tare (None: none sent)
    boot_pattern: str | None = None  # regex found in the sketch's boot banner lines
    read_timeout_s: float = 3.0      # default wait for one line: covers the sketch's period


PRESETS: dict[str, Preset] = {
    # olkal/HX711_ADC example Read_1x_load_cell: "Load_cell output val: 12.34"
    "hx711_adc": Preset(rf"Load_cell output val:\s*(?P<value>{FLOAT})", 57600, "g", "t",
                        r"Tare complete",
                        r"Starting\.\.\.|Startup is complete|Timeout, check MCU>HX711 wiring"),
    # bogde/HX711 0.7.5 HX711_basic_example (and _retry_, _timeout_): "HX711 reading: 81234",
    # raw ADC counts at 57600 baud every 1-1.5 s; no banner, never reads serial: no tare
    "bogde": Preset(r"HX711 reading: (?P<value>-?\d+)", 57600, "raw", None, None, None, 3.0),
    # bogde/HX711 0.7.5 HX711_full_example: "one reading:\t1.2\t| average:\t1.3" at 38400
    # baud about every 6.2 s (11 conversions at 10 SPS + delay(5000)); never reads serial
    "bogde_full": Preset(rf"one reading:\s*{FLOAT}\s*\|\s*average:\s*(?P<value>{FLOAT})",
                         38400, "g", None, None,
                         r"HX711 Demo|Initializing the scale|(?:Before|After) setting up the scale:",
                         10.0),
    # sketches that print one bare number per line; their banner (if any) is text: a
    # printable line with a word of 4+ letters (not Arduino's "nan"/"inf"/"ovf")
    "bare_float": Preset(rf"\s*(?P<value>{FLOAT})\s*", 115200, "g", "t", None,
                         r"^[ -~\t]*[A-Za-z]{4,}[ -~\t]*$"),
}


@dataclass(frozen=True)
class LineValue:
    value: float
    unit: str | None


def compile_pattern(pattern: str) -> re.Pattern[str]:
    """Compile a line pattern; it must have a group named ``value`` (or ``value2``)."""
    try:
        rx = re.compile(pattern)
    except re.error as exc:
        raise ValueError(f"pattern {pattern!r}: {exc}") from None
    if "value" not in rx.groupindex:
        raise ValueError(f"pattern {pattern!r} has no (?P<value>...) group")
    return rx


def parse_value_line(line: bytes, pattern: re.Pattern[str]) -> LineValue:
    """The number in ``line`` if the whole line matches ``pattern``; else FrameError.

    Only finite numbers are accepted (``nan``/``inf`` printed by a broken sketch are
    garbage, not readings).
    """
    line = line.rstrip(b"\r\n")
    try:
        text = line.decode("ascii")
    except UnicodeDecodeError:
        raise FrameError(f"not ASCII: {line!r}") from None
    if any(ord(c) < 0x20 and c != "\t" for c in text):
        raise FrameError(f"control bytes in {line!r}")
    m = pattern.fullmatch(text)
    if not m:
        raise FrameError(f"line does not match the pattern: {line!r}")
    groups = m.groupdict()
    raw = groups.get("value") or groups.get("value2")
    if raw is None:
        raise FrameError(f"no value in {line!r}")
    try:
        value = float(raw)
    except ValueError:
        raise FrameError(f"bad number {raw!r}") from None
    if not math.isfinite(value):
        raise FrameError(f"non-finite number in {line!r}")
    return LineValue(value, groups.get("unit"))


def compile_boot_pattern(pattern: str | None) -> re.Pattern[str] | None:
    """Compile a banner pattern; ``None`` or ``""`` means the sketch has no known banner."""
    if not pattern:
        return None
    try:
        return re.compile(pattern)
    except re.error as exc:
        raise ValueError(f"boot_pattern {pattern!r}: {exc}") from None


def is_boot_line(line: bytes, boot: re.Pattern[str] | None) -> bool:
    """True when ``line`` is part of the sketch's boot banner (``boot`` found in it).

    Pure; bytes outside ASCII are read as Latin-1, so power-on junk glued to a banner line
    does not hide it. ``boot=None`` (no banner known) is never a boot line.
    """
    if boot is None:
        return False
    return boot.search(line.rstrip(b"\r\n").decode("latin-1")) is not None


def format_value_line(preset: str, value: float, decimals: int = 2) -> bytes:
    """A line as the preset's sketch prints it (for tests and documentation)."""
    number = f"{value:.{decimals}f}"
    if preset == "hx711_adc":
        return f"Load_cell output val: {number}\r\n".encode("ascii")
    if preset == "bogde":
        return f"HX711 reading: {round(value)}\r\n".encode("ascii")
    if preset == "bogde_full":
        return f"one reading:\t{number}\t| average:\t{number}\r\n".encode("ascii")
    if preset == "bare_float":
        return f"{number}\r\n".encode("ascii")
    raise ValueError(f"unknown preset {preset!r}; known: {', '.join(PRESETS)}")


_BENCH_RX = compile_pattern(PRESETS["hx711_adc"].pattern)
register_parser_benchmark("line_regex", b"Load_cell output val: 12.34\r\n",
                          lambda line: parse_value_line(line, _BENCH_RX))


@register_driver
class LineRegexBalance(ContinuousMixin, LinkTailMixin, Balance):
    """A load cell behind a third-party Arduino sketch that prints one value per line.

    Options: ``preset`` (``hx711_adc`` default, ``bogde``, ``bogde_full``, ``bare_float``), ``pattern``
    (regex with ``(?P<value>...)``), ``unit`` (unit of the printed value after
    calibration: ``g`` default, ``kg``, ``N``, or ``raw``), ``scale`` (1), ``offset`` (0),
    ``capacity`` (in ``unit``; beyond it a reading is overload), ``tare_command`` (``t``),
    ``tare_reply`` (regex), ``tare_settle_s`` (1.5, wait after a tare the
    sketch does not confirm), ``stable_std`` and ``stable_window`` (8), ``eol`` (``"CRLF"``),
    ``boot_pattern`` (regex of the sketch's banner lines; ``""``: none), ``read_timeout_s``
    (default wait for a line, the preset's: 10 s for ``bogde_full``). The ``bogde`` presets
    have no tare command (the sketches never read the port): ``zero()`` refuses; subtract
    a zero with ``offset``.

    ``resets_seen`` counts banners that followed a value line (the device rebooted during
    use); the first reading after one is flagged ``device_reset`` and ``tare_lost``.
    """

    protocol = "line_regex"
    option_names = frozenset({"boot_pattern", "capacity", "eol", "offset", "pattern", "preset",
                              "read_timeout_s", "scale", "stable_std",
                              "stable_window", "tare_command", "tare_reply", "tare_settle_s", "unit"})
    default_serial = {"baudrate": 57600, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        preset_name = str(options.get("preset", "hx711_adc"))
        if preset_name not in PRESETS:
            raise ValueError(f"preset {preset_name!r}: known presets are {', '.join(PRESETS)}")
        preset = PRESETS[preset_name]
        self.preset = preset_name
        self.pattern = compile_pattern(str(options.get("pattern", preset.pattern)))
        self.unit = str(options.get("unit", preset.unit))
        self.scale = float(options.get("scale", 1.0))
        self.offset = float(options.get("offset", 0.0))
        capacity = options.get("capacity")
        self.capacity = float(capacity) if capacity is not None else None
        tare_command = options.get("tare_command", preset.tare_command)
        self.tare_command = None if tare_command in (None, "") else str(tare_command)
        self.read_timeout_s = float(options.get("read_timeout_s", preset.read_timeout_s))
        reply = options.get("tare_reply", preset.tare_reply)
        self.tare_reply = re.compile(str(reply)) if reply else None
        self.tare_settle_s = float(options.get("tare_settle_s", 1.5))
        boot = options.get("boot_pattern", preset.boot_pattern)
        self.boot_pattern = compile_boot_pattern(str(boot) if boot is not None else None)
        self.resets_seen = 0
        self._booting = True        # banner lines before the first value: the boot we opened into
        self._reset_pending = False
        stable_std = options.get("stable_std")
        self.stable_std = float(stable_std) if stable_std is not None else None
        self.window: deque[float] = deque(maxlen=int(options.get("stable_window", 8)))
        self.serial_expected = self.serial_defaults(options)
        eol = eol_bytes(str(options.get("eol", "CRLF")))
        self.read_eol = b"\r" if eol == b"\r" else b"\n"
        self.link = LineLink(port, clock, self.name, expected_serial=self.serial_expected,
                             write_eol=eol, read_eol=self.read_eol, on_unsolicited=self._unsolicited)
        if self.unit != "raw":
            try:
                to_si(1.0, self.unit)
            except UnitError as exc:
                raise ValueError(str(exc)) from None

    @classmethod
    def serial_defaults(cls, options: dict[str, Any]) -> dict[str, Any]:
        """Serial settings of the sketch the options name (its preset's baud rate)."""
        preset = PRESETS.get(str(options.get("preset", "hx711_adc")), PRESETS["hx711_adc"])
        return dict(cls.default_serial, baudrate=preset.baudrate)

    def _is_boot(self, line: bytes) -> bool:
        """A banner line, and not the sketch's tare confirmation."""
        if not is_boot_line(line, self.boot_pattern):
            return False
        return self.tare_reply is None or not self.tare_reply.search(line.decode("latin-1"))

    def _accept(self, line: bytes) -> LineValue | None:
        try:
            return parse_value_line(line, self.pattern)
        except FrameError:
            if self._is_boot(line):
                return None  # a valid line, not a value: the link hands it to _unsolicited
            raise

    # ---- device reset: the boot banner again -----------------------------------------------
    def _unsolicited(self, _t: float, line: bytes) -> None:
        """Lines that are not the awaited value (banner, stale values dropped before a read)."""
        if self._is_boot(line):
            self._note_boot_line()
        else:
            try:
                parse_value_line(line, self.pattern)
            except FrameError:
                return
            self._booting = False

    def _note_boot_line(self) -> None:
        if not self._booting:  # a banner after values: the sketch rebooted and re-tared
            self.resets_seen += 1
            self._reset_pending = True
            self.window.clear()
        self._booting = True

    def _reading(self, t: float, line: bytes, parsed: LineValue) -> Reading:
        self._booting = False
        flags: set[str] = set()
        if self._reset_pending:
            self._reset_pending = False
            flags |= {"device_reset", "tare_lost"}
        shown = (parsed.value - self.offset) * self.scale
        unit = parsed.unit or self.unit
        # a printed saturation code is overload whatever the calibration
        # (docs/explanation/device-rules.md#driver-rules, rule 4)
        overload = parsed.value >= HX711_MAX or parsed.value <= HX711_MIN
        overload = overload or (self.capacity is not None and abs(shown) > self.capacity)
        if unit == "raw":
            quantity, value, si_unit = "adc_counts", shown, "1"
        else:
            try:
                quantity, value, si_unit = to_si(shown, unit)
            except UnitError as exc:
                raise DeviceReplyError(self.name, "stream", line, str(exc)) from None
        if overload:
            self.window.clear()
            return Reading(t, quantity, float("nan"), si_unit, stable=False, overload=True,
                           raw=line, device=self.name, flags=frozenset(flags | {"overload"}))
        self.window.append(value)
        if self.stable_std is None:
            stable = True
            flags.add("stability_unknown")
        else:
            full = len(self.window) == self.window.maxlen
            stable = full and statistics.pstdev(self.window) <= self._stable_std_si(unit)
        return Reading(t, quantity, value, si_unit, stable=stable, overload=False, raw=line,
                       device=self.name, flags=frozenset(flags))

    def _stable_std_si(self, unit: str) -> float:
        assert self.stable_std is not None
        if unit == "raw":
            return self.stable_std * abs(self.scale)
        return to_si(self.stable_std * abs(self.scale), unit)[1]

    # ---- continuous: the sketch always streams; the reader just keeps every line --------
    def _begin_stream(self) -> None:
        self.link.discard_stale("stream")

    def _end_stream(self) -> None:
        pass

    def _stream_reading(self, t: float, line: bytes) -> Reading | None:
        parsed = self._accept(line)
        if parsed is None:
            self._note_boot_line()
            return None
        return self._reading(t, line, parsed)

    def identify(self) -> dict[str, Any]:
        """Sketches do not identify themselves: the preset and pattern in use."""
        return {"protocol": self.protocol, "preset": self.preset, "pattern": self.pattern.pattern}

    def read(self, timeout: float | None = None) -> Reading:
        """The next value line received after this call (older buffered lines are dropped);
        ``timeout`` defaults to ``read_timeout_s`` (the preset's line period covered)."""
        timeout = self.read_timeout_s if timeout is None else timeout
        if self.stream is not None:
            return self.stream.wait_new(self.clock.now(), timeout)
        self.link.discard_stale("stream")
        t, line, parsed = self.link.exchange(None, self._accept, timeout)
        return self._reading(t, line, parsed)

    def zero(self, timeout: float = 20.0) -> None:
        """Send the tare command (``t``); wait for the sketch's confirmation line if it has one,
        else for the next value line. A sketch without a tare command: DeviceError."""
        if self.tare_command is None:
            raise DeviceError(self.name, "tare", b"",
                              f"preset {self.preset!r}: the sketch reads no serial input, so it "
                              "cannot tare; set option offset (in printed units) instead")
        with self.paused():
            self._zero(timeout)

    def _zero(self, timeout: float) -> None:
        self.window.clear()
        assert self.tare_command is not None
        self.link.discard_stale(self.tare_command)
        rx = self.tare_reply

        def accept(line: bytes) -> bool | None:
            if rx is not None:
                text = line.decode("ascii", "replace")
                return True if rx.search(text) else None
            return True if self._accept(line) is not None else None

        self.link.send(self.tare_command)
        if rx is None:  # no confirmation line: give the sketch its averaging time
            self.clock.sleep(self.tare_settle_s)
            self.link.discard_stale(self.tare_command)
        self.link.exchange(None, accept, timeout)
