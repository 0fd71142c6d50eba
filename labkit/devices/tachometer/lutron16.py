"""Lutron 16-byte RS-232 stream (docs/reference/devices-tach-motor.md#lutron16-lutron-16-byte-stream):
hand-held and panel tachometers.

The meter streams continuously at 9600 8N1; the host never writes. One frame is exactly
16 bytes, D15 first::

    D15  STX (0x02)
    D14  '4'
    D13  display: '1' main, '2' second ('1'..'9', 'A'..'C' on multi-channel meters)
    D12 D11  annunciator (unit) code, two characters, meter-specific (digits on most
             meters; letters such as ``B2`` on some)
    D10  polarity '0' positive, '1' negative
    D9   decimal point position from the right, '0'..'3'
    D8..D1  reading, 8 digits, most significant first
    D0   CR (0x0D)

Resync (docs/explanation/device-rules.md#driver-rules, rule 2): scan for 0x02 and accept only when the 16th
byte is 0x0D;
otherwise drop that 0x02 and scan again. Over-range ("no signal", "OL") frames carry
non-digit characters in D8..D1; they become readings flagged ``overload`` with value NaN,
never a number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.devices.tachometer.streaming import StreamingTachometer
from labkit.errors import DeviceTimeout
from labkit.readings import Reading
from labkit.units import rpm_to_rad_s

STX = 0x02
CR = 0x0D
FRAME_LEN = 16
DISPLAY_CHARS = b"123456789ABC"
#: characters an over-range / no-signal reading field is made of (no digits) [U]
OVER_RANGE_CHARS = frozenset(b" -OLE")

#: Annunciator codes of the Lutron manuals that are *not* a speed of rotation; a
#: tachometer driver refuses frames carrying them instead of calling them RPM
#: (03 and 93-98: the unit tables of Lutron's tachometer/vibration manuals).
NON_ROTATION_ANNUNCIATORS = {
    "01": "degC", "02": "degF", "03": "%", "08": "m/s", "10": "km/h", "11": "ft/min",
    "12": "mile/h", "17": "dB", "19": "PPM", "57": "g", "93": "mm/s", "94": "mm",
    "95": "cm/s", "96": "inch", "98": "inch/s",
}

#: display unit of the number -> factor to rad/s
ROTATION_UNITS = {"rpm": rpm_to_rad_s(1.0), "rps": 2.0 * math.pi}


@dataclass(frozen=True)
class Lutron16Frame:
    """One decoded frame. ``value`` is None when the meter shows over-range/no signal."""

    display: str
    annunciator: str
    value: float | None
    raw: bytes

    @property
    def over_range(self) -> bool:
        return self.value is None


def parse_lutron16(frame: bytes) -> Lutron16Frame:
    """Decode one 16-byte frame; raise ValueError naming what is wrong."""
    if len(frame) != FRAME_LEN:
        raise ValueError(f"frame has {len(frame)} bytes, expected {FRAME_LEN}")
    if frame[0] != STX or frame[-1] != CR:
        raise ValueError("frame does not start with STX and end with CR")
    if frame[1:2] != b"4":
        raise ValueError(f"D14 is {frame[1:2]!r}, expected '4'")
    display = frame[2:3]
    if display not in DISPLAY_CHARS or len(display) != 1:
        raise ValueError(f"display byte {display!r} unknown")
    annunciator = frame[3:5]
    if not (annunciator.isalnum() and annunciator.isascii()):
        raise ValueError(f"annunciator {annunciator!r} is not two letters or digits")
    polarity, point = frame[5:6], frame[6:7]
    if polarity not in (b"0", b"1"):
        raise ValueError(f"polarity byte {polarity!r} is not '0' or '1'")
    if point not in (b"0", b"1", b"2", b"3"):
        raise ValueError(f"decimal point byte {point!r} is not '0'..'3'")
    digits = frame[7:15]
    if digits.isdigit() and digits.isascii():
        magnitude = int(digits) / 10 ** int(point)
        value: float | None = -magnitude if polarity == b"1" else magnitude
    elif all(b in OVER_RANGE_CHARS for b in digits):
        value = None
    else:
        raise ValueError(f"reading field {digits!r} is neither digits nor over-range")
    return Lutron16Frame(display.decode(), annunciator.decode(), value, bytes(frame))


class Lutron16Framer:
    """Cut a byte stream into 16-byte STX...CR frames, resyncing on every bad start."""

    def __init__(self, max_buffer: int = 4096) -> None:
        self.buffer = bytearray()
        self.max_buffer = max_buffer
        self.dropped = 0  # bytes thrown away while resyncing
        self.bytes_seen = 0  # every byte fed, frames or not (tells "silent" from "garbage")

    def feed(self, data: bytes) -> list[bytes]:
        self.bytes_seen += len(data)
        self.buffer += data
        frames: list[bytes] = []
        while True:
            start = self.buffer.find(STX)
            if start < 0:
                self.dropped += len(self.buffer)
                self.buffer.clear()
                return frames
            if start:
                self.dropped += start
                del self.buffer[:start]
            if len(self.buffer) < FRAME_LEN:
                if len(self.buffer) > self.max_buffer:  # pragma: no cover - cannot happen
                    self.buffer.clear()
                return frames
            if self.buffer[FRAME_LEN - 1] == CR:
                frames.append(bytes(self.buffer[:FRAME_LEN]))
                del self.buffer[:FRAME_LEN]
            else:
                self.dropped += 1
                del self.buffer[:1]


@register_driver
class Lutron16Tachometer(StreamingTachometer):
    """Lutron-format tachometer (DT-2236/DT-2268 class and re-badges).

    Options: ``display`` ('1' main, default), ``unit`` ('rpm' default, or 'rps': what the
    displayed number means), ``rpm_code`` (two digits: accept only frames with this
    annunciator; by default any code except the known non-rotation units).
    """

    protocol = "lutron16"
    option_names = frozenset({"display", "rpm_code", "unit"})
    default_serial = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __init__(self, port: Any, clock: Any, name: str = "", **options: Any):
        self.display = str(options.get("display", "1"))
        unit = str(options.get("unit", "rpm")).lower()
        if unit not in ROTATION_UNITS:
            raise ValueError(f"lutron16 option unit={unit!r}: expected one of {sorted(ROTATION_UNITS)}")
        self.to_rad_s = ROTATION_UNITS[unit]
        code = options.get("rpm_code")
        code = None if code in (None, "") else str(code).strip()
        self.rpm_code = f"{int(code):02d}" if code and code.isdigit() else code
        super().__init__(port, clock, name, **options)

    def make_framer(self) -> Lutron16Framer:
        return Lutron16Framer()

    def wait_reading(self, timeout: float = 2.0) -> Reading:
        """The first reading received after this call; never an older (stale) one.

        The meter only streams, so silence is the only sign that it was switched off or its
        cable pulled at the meter end (the host's port stays open). After ``timeout`` s
        without a new reading this raises :class:`~labkit.errors.DeviceTimeout` naming the
        device, what it waited for, the last bytes seen and whether any bytes came at all.
        """
        framer = self.reader.framer
        assert isinstance(framer, Lutron16Framer)
        seen_before, rejected_before = framer.bytes_seen, self.frames_rejected
        try:
            return super().wait_reading(timeout)
        except DeviceTimeout as exc:
            last = self.latest()
            ago = (f"last reading {self.clock.now() - last.t:.1f} s ago" if last is not None
                   else "no reading since open")
            if framer.bytes_seen == seen_before:
                why = ("the meter sent nothing: switched off, its RS-232 output off, "
                       "or the cable pulled at the meter")
            elif self.frames_rejected > rejected_before:
                why = ("only frames this driver refuses (other display or unit; "
                       "check the display/rpm_code options)")
            else:
                why = "only bytes that are no 16-byte frame; check baud rate (9600 8N1)"
            raise DeviceTimeout(self.name, "stream", exc.last_bytes,
                                f"no reading in {timeout} s, waiting for a 16-byte frame "
                                f"of display {self.display}: {why}; {ago}") from None

    def parse_frame(self, t: float, frame: bytes) -> Reading | None:
        decoded = parse_lutron16(frame)
        if decoded.display != self.display:
            return None
        if self.rpm_code is not None and decoded.annunciator != self.rpm_code:
            raise ValueError(f"annunciator {decoded.annunciator} is not rpm_code {self.rpm_code}")
        if decoded.annunciator in NON_ROTATION_ANNUNCIATORS:
            raise ValueError(f"annunciator {decoded.annunciator} is "
                             f"{NON_ROTATION_ANNUNCIATORS[decoded.annunciator]}, not a rotation speed")
        if self.rpm_code is None and not decoded.annunciator.isdigit():
            raise ValueError(f"annunciator {decoded.annunciator} is no rotation unit code "
                             "(set rpm_code if this meter uses it for RPM)")
        if decoded.value is None:
            return Reading(t, "angular_speed", math.nan, "rad/s", stable=False, overload=True,
                           raw=frame, device=self.name, flags=frozenset({"over_range"}))
        return Reading(t, "angular_speed", decoded.value * self.to_rad_s, "rad/s",
                       raw=frame, device=self.name)


#: an example frame of the protocol: main display, +1234.5 (annunciator 00 as a placeholder)
SAMPLE_FRAME = b"\x02" + b"4" + b"1" + b"00" + b"0" + b"1" + b"00012345" + b"\r"

register_parser_benchmark("lutron16", SAMPLE_FRAME, parse_lutron16)
