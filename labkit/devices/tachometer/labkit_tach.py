"""The labkit pulse-counter tachometer line protocol
(docs/reference/devices-tach-motor.md#labkit_tach-the-labkit-pulse-tachometer-labkit-defined).

An Arduino (``firmware/labkit_tach``) times pulses from an optical or Hall sensor with the
period method, averaging over every pulse of an output window, and prints one line per
window (115200 8N1, LF)::

    T,<seq>,<t_ms>,<rpm>,<period_us>,<pulses>,<flags>
      seq        line counter (restarts at 0 after a reset); a line with the seq of the one
                 before is the same measurement again: dropped, counted in lines_repeated
      t_ms       device millis() at the end of the window
      rpm        60e6 / (period_us * ppr), mechanical revolutions per minute
      period_us  mean pulse period in the window (0 when no pulse)
      pulses     pulses counted in the window
      flags      0 ok | Z zero-speed timeout | O overflow/too fast | N noisy (glitch rejected)

Host commands ``PPR <n>``, ``RATE <hz>``, ``ZTO <ms>`` answer ``OK`` or ``ERR <text>``;
``ID?`` answers ``ID labkit-tach <ver>``. At boot (also after the DTR reset that opening
the port causes) the device prints ``# labkit-tach <ver> ppr=<n> rate=<hz> zto=<ms>``; lines
starting with ``#`` are comments. At 1 pulse/rev, 100 000 RPM is a 600 us period, well
inside the firmware's 50 us floor.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Any

from labkit.devices.link import LineFramer, ReplyQueue
from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.devices.sketch_commands import (
    SketchCommands,
    is_reply,
    parse_flag_letters,
    parse_sketch_banner,
    strip_sketch_junk,
)
from labkit.devices.tachometer.streaming import StreamingTachometer
from labkit.readings import Reading
from labkit.units import rpm_to_rad_s

FLAG_NAMES = {"Z": "zero_speed", "O": "over_range", "N": "noisy"}
#: relative disagreement allowed between rpm and 60e6/(period_us*ppr) (print rounding)
CONSISTENCY_TOLERANCE = 0.005


@dataclass(frozen=True)
class TachSample:
    """One ``T,...`` line, decoded but not yet converted to SI."""

    seq: int
    t_ms: int
    rpm: float
    period_us: float
    pulses: int
    flags: frozenset[str]


def _non_negative_number(text: bytes, what: str) -> float:
    if not text or not all(c in b"0123456789." for c in text) or text.count(b".") > 1 or text == b".":
        raise ValueError(f"{what} {text!r} is not a non-negative decimal number")
    return float(text)


def _non_negative_int(text: bytes, what: str) -> int:
    if not (text.isdigit() and text.isascii()) or len(text) > 12:
        raise ValueError(f"{what} {text!r} is not a non-negative integer")
    return int(text)


def parse_tach_sample(line: bytes) -> TachSample:
    """Decode a ``T,<seq>,<t_ms>,<rpm>,<period_us>,<pulses>,<flags>`` line (no LF).

    Raises ValueError naming the bad field. Also checks the line against itself: a
    zero-speed line must say 0 rpm, and an ok line must not claim pulses with a zero period.
    """
    fields = line.strip().split(b",")
    if len(fields) != 7 or fields[0] != b"T":
        raise ValueError(f"not a T line with 7 fields: {line[:40]!r}")
    seq = _non_negative_int(fields[1], "seq")
    t_ms = _non_negative_int(fields[2], "t_ms")
    rpm = _non_negative_number(fields[3], "rpm")
    period_us = _non_negative_number(fields[4], "period_us")
    pulses = _non_negative_int(fields[5], "pulses")
    flags = parse_flag_letters(fields[6], FLAG_NAMES)
    if "zero_speed" in flags and rpm != 0.0:
        raise ValueError(f"zero-speed line with rpm {rpm}")
    if not flags and rpm > 0 and period_us == 0:
        raise ValueError("rpm without a pulse period")
    return TachSample(seq, t_ms, rpm, period_us, pulses, flags)


def consistent_with_ppr(sample: TachSample, ppr: int) -> bool:
    """True when rpm agrees with 60e6/(period_us*ppr) (catches corrupted digits)."""
    if sample.flags & {"zero_speed", "over_range"} or sample.period_us == 0:
        return True
    expected = 60e6 / (sample.period_us * ppr)
    return abs(sample.rpm - expected) <= CONSISTENCY_TOLERANCE * expected + 0.2


def parse_banner(line: bytes) -> dict[str, str] | None:
    """``# labkit-tach 1.0 ppr=1 rate=10 zto=1000`` -> {"version": "1.0", "ppr": "1", ...}.

    None for any other line (other ``#`` lines are plain comments).
    """
    return parse_sketch_banner(line, "labkit-tach")


def format_command(name: str, value: int | None = None) -> bytes:
    """``PPR 2``/``RATE 50``/``ZTO 500``/``ID?`` as bytes with LF."""
    if name == "ID?":
        return b"ID?\n"
    if name not in ("PPR", "RATE", "ZTO") or value is None or int(value) <= 0:
        raise ValueError(f"bad labkit-tach command {name} {value}")
    return f"{name} {int(value)}\n".encode("ascii")


LINE_STARTS = (b"T,", b"OK", b"ERR", b"ID ", b"#")


def strip_junk(line: bytes) -> bytes:
    """Drop bytes before the first known line start (power-on junk, noise on the wire)."""
    return strip_sketch_junk(line, LINE_STARTS)


@register_driver
class LabkitTachometer(SketchCommands, StreamingTachometer):
    """Driver of the labkit Arduino pulse tachometer.

    Options: ``ppr`` (pulses per revolution, default 1: always sent on open), ``rate_hz``
    (line rate, default: the device's), ``zto_ms`` (zero-speed timeout, default: the
    device's), ``boot_timeout_s`` (wait for the banner or data after open, default 3 s:
    opening an Arduino's port resets it), ``reply_timeout_s`` (default 0.5 s).
    After a reset (a new boot banner) the options are sent again and the next reading
    carries the flag ``reset``.
    """

    protocol = "labkit_tach"
    option_names = frozenset({"boot_timeout_s", "ppr", "rate_hz", "reply_timeout_s", "zto_ms"})
    default_serial = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __init__(self, port: Any, clock: Any, name: str = "", **options: Any):
        self.ppr = int(options.get("ppr", 1))
        if self.ppr < 1:
            raise ValueError(f"labkit_tach option ppr={self.ppr}: must be >= 1")
        self.rate_hz = options.get("rate_hz")
        self.zto_ms = options.get("zto_ms")
        self.reply_timeout_s = float(options.get("reply_timeout_s", 0.5))
        self.banner: dict[str, str] = {}
        self.resets = 0
        self.lines_lost = 0
        self.lines_repeated = 0
        self._state_lock = threading.Lock()
        self._alive = False
        self._flag_reset = False
        self._last_seq: int | None = None
        self.replies = ReplyQueue(port, clock, name, check=self._check_reader,
                                  tail=lambda: self.reader.last_bytes)
        super().__init__(port, clock, name, **options)
        try:
            self._wait_alive(float(options.get("boot_timeout_s", 3.0)), "T line")
            self._configure()
        except Exception:
            self.close()
            raise

    def make_framer(self) -> LineFramer:
        return LineFramer(b"\n", max_len=128)

    # ---- frames -------------------------------------------------------------------------
    def parse_frame(self, t: float, frame: bytes) -> Reading | None:
        line = strip_junk(frame.strip())
        if not line:
            return None
        if line.startswith(b"#"):
            banner = parse_banner(line)
            if banner is not None:
                self._note_banner(banner, self._state_lock)
            return None
        if is_reply(line):
            self.replies.put(line)
            return None
        sample = parse_tach_sample(line)
        self._alive = True  # a well-formed line, even at another PPR: the device is there
        if not consistent_with_ppr(sample, self.ppr):
            raise ValueError(f"rpm {sample.rpm} disagrees with period {sample.period_us} us, ppr {self.ppr}")
        with self._state_lock:
            if self._last_seq is not None and sample.seq == self._last_seq:
                self.lines_repeated += 1  # the same measurement again: no new reading (a stuck
                return None               # firmware or link; the loop's tach_timeout sees it)
            if self._last_seq is not None and sample.seq > self._last_seq + 1:
                self.lines_lost += sample.seq - self._last_seq - 1
            self._last_seq = sample.seq
            flags = set(sample.flags)
            if self._flag_reset:
                flags.add("reset")
                self._flag_reset = False
        if "over_range" in flags:
            return Reading(t, "angular_speed", math.nan, "rad/s", stable=False, overload=True,
                           raw=frame, device=self.name, flags=frozenset(flags))
        return Reading(t, "angular_speed", rpm_to_rad_s(sample.rpm), "rad/s",
                       stable="noisy" not in flags, raw=frame, device=self.name,
                       flags=frozenset(flags))

    # ---- commands -----------------------------------------------------------------------
    def command(self, text: str, value: int | None = None) -> bytes:
        """Send one command, return its reply line (``OK``/``ID ...``); ERR raises."""
        data = format_command(text, value)
        return self._exchange(data, data.decode().strip())

    def write(self, data: bytes, label: str) -> None:
        """Write to the device; a dead port becomes DeviceDisconnected naming the command."""
        self.replies.write(data, label)

    def config_commands(self) -> list[tuple[str, int]]:
        commands = [("PPR", self.ppr)]
        if self.rate_hz is not None:
            commands.append(("RATE", int(self.rate_hz)))
        if self.zto_ms is not None:
            commands.append(("ZTO", int(self.zto_ms)))
        return commands

    def _configure(self) -> None:
        for name, value in self.config_commands():
            self.command(name, value)

    def _resend_config(self) -> None:
        """After a device reset (called by the reader): send the settings, not waiting for
        the OKs (a reader must not block); lines at the wrong PPR fail the consistency check
        until the device has them."""
        try:
            with self.replies.write_lock:
                for name, value in self.config_commands():
                    self.port.write(format_command(name, value))
        except Exception:  # noqa: BLE001 - a dead port is reported by the reader itself
            pass

    def identify(self) -> dict[str, Any]:
        reply = self.command("ID?").decode("ascii", "replace").split()
        out: dict[str, Any] = {"model": reply[1] if len(reply) > 1 else "",
                               "firmware": reply[2] if len(reply) > 2 else "", "ppr": self.ppr}
        return out


SAMPLE_LINE = b"T,1234,123400,24000.0,2500.0,40,0"
register_parser_benchmark("labkit_tach", SAMPLE_LINE, parse_tach_sample)
