"""The labkit strobe's line protocol as pure functions (docs/reference/devices-strobe.md,
``firmware/labkit_strobe``): parsing its status lines and banner, formatting its commands.

The strobe (115200 8N1, LF) prints one status line every 1/RATE s::

    S,<seq>,<t_ms>,<f_rot_hz>,<f_strobe_hz>,<phase_deg>,<flags>
      seq          line counter (restarts at 0 after a reset)
      t_ms         device milliseconds since boot at the end of the window
      f_rot_hz     rotor frequency: revolutions in the window over their ticks (4 decimals)
      f_strobe_hz  strobe frequency: flash intervals in the window over their ticks
      phase_deg    rotor angle after the pulse at the window's last flash, 0-360 (1 decimal)
      flags        0 ok, else letters (see FLAG_NAMES)

Commands ``OFFSET <hz>``, ``WIDTH <us>``, ``DIV <m>``, ``RATE <hz>``, ``ON``, ``OFF`` answer
``OK`` or ``ERR <text>``; ``ID?`` answers ``ID labkit-strobe <ver>``. The boot banner is
``# labkit-strobe <ver> offset=<hz> width=<us> div=<m> rate=<hz>``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from labkit.devices.sketch_commands import parse_flag_letters, parse_sketch_banner, strip_sketch_junk
from labkit.readings import Reading

#: status-line flag letters -> names
FLAG_NAMES = {
    "Z": "no_pulses", "L": "unlocked", "N": "noisy", "X": "lamp_off", "W": "width_cut",
    "R": "offset_out_of_range", "O": "rotor_out_of_range", "M": "flash_missed", "S": "flash_stretched",
}
#: what each flag means and whether a strobe-derived result may be wrong because of it
STROBE_FLAGS: dict[str, tuple[bool, str]] = {
    "no_pulses": (True, "no rotor pulse for 4 periods: the lamp is dark"),
    "unlocked": (True, "the flashes were not locked to the rotor for (part of) the window"),
    "noisy": (True, "a noise pulse on the rotor input was rejected"),
    "lamp_off": (False, "the lamp was switched off (OFF)"),
    "width_cut": (False, "the flash width was cut to a quarter of the rotor period"),
    "offset_out_of_range": (True, "the offset needs more than 1/4 revolution per flash: no flashes"),
    "rotor_out_of_range": (True, "rotor below 5 Hz or above 4 kHz: not locked"),
    "flash_missed": (True, "a flash could not be scheduled in time and was skipped"),
    "flash_stretched": (True, "a flash's end was held up by another interrupt (widths of a few us)"),
}
COMMANDS = ("OFFSET", "WIDTH", "DIV", "RATE")
LIMITS = {"OFFSET": (-100.0, 100.0), "WIDTH": (1, 1000), "DIV": (1, 100), "RATE": (1, 50)}
LINE_STARTS = (b"S,", b"OK", b"ERR", b"ID ", b"#")


@dataclass(frozen=True)
class StrobeStatus:
    """One status line. ``t`` is the host clock time (s) the bytes arrived; frequencies in Hz.

    ``divider`` is the flash divider the driver had set (the line does not carry it);
    ``apparent_hz`` = f_rot - m * f_strobe, the offset the strobe shows (None without flashes).
    """

    t: float
    seq: int
    t_ms: int
    rotor_hz: float
    strobe_hz: float
    phase_deg: float
    flags: frozenset[str] = field(default_factory=frozenset)
    raw: bytes = b""
    device: str = ""
    divider: int = 1

    @property
    def apparent_hz(self) -> float | None:
        if self.rotor_hz <= 0.0 or self.strobe_hz <= 0.0:
            return None
        return self.rotor_hz - self.divider * self.strobe_hz

    @property
    def locked(self) -> bool:
        """Flashing in lock for the whole window, with no flag that may make it wrong."""
        return self.strobe_hz > 0.0 and not any(STROBE_FLAGS.get(f, (True, ""))[0] for f in self.flags)

    def reading(self) -> StrobeReading:
        """The line as a reading for ``readings/ROLE.jsonl`` (the strobe frequency, its lock, and
        everything else the line said beside it)."""
        return StrobeReading(t=self.t, quantity="strobe_frequency", value=self.strobe_hz, unit="Hz",
                             stable=self.locked, raw=self.raw, device=self.device, flags=self.flags,
                             rotor_hz=self.rotor_hz, phase_deg=self.phase_deg, seq=self.seq, t_ms=self.t_ms,
                             divider=self.divider)

    def as_json(self) -> dict[str, Any]:
        """The probe's JSON object: ``value`` is the strobe frequency (Hz), ``stable`` its lock."""
        return {
            "t": self.t, "quantity": "strobe_frequency", "value": self.strobe_hz, "unit": "Hz",
            "stable": self.locked, "overload": False, "flags": sorted(self.flags),
            "raw": self.raw.decode("latin-1"), "seq": self.seq, "t_ms": self.t_ms,
            "rotor_hz": self.rotor_hz, "strobe_hz": self.strobe_hz, "phase_deg": self.phase_deg,
            "apparent_hz": self.apparent_hz, "divider": self.divider,
        }


@dataclass(frozen=True)
class StrobeReading(Reading):
    """A status line kept as a reading: ``value`` the strobe frequency [Hz], ``stable`` its lock
    (:attr:`StrobeStatus.locked`), ``flags`` the line's flags; the rotor frequency, phase,
    sequence number, device time and the divider the driver had set beside them."""

    rotor_hz: float = 0.0
    phase_deg: float = 0.0
    seq: int = 0
    t_ms: int = 0
    divider: int = 1

    def as_json(self) -> dict[str, Any]:
        apparent = self.rotor_hz - self.divider * self.value if self.rotor_hz > 0 and self.value > 0 else None
        return {**super().as_json(), "rotor_hz": self.rotor_hz, "strobe_hz": self.value,
                "apparent_hz": apparent, "phase_deg": self.phase_deg, "seq": self.seq, "t_ms": self.t_ms,
                "divider": self.divider}


def _decimal(text: bytes, what: str, places: int) -> float:
    """A non-negative decimal with exactly ``places`` digits after the point."""
    whole, dot, frac = text.partition(b".")
    if not (dot and whole.isdigit() and frac.isdigit() and whole.isascii() and frac.isascii()
            and len(frac) == places and len(whole) <= 9):
        raise ValueError(f"{what} {text[:20]!r} is not a decimal with {places} places")
    return float(text)


def _integer(text: bytes, what: str) -> int:
    if not (text.isdigit() and text.isascii()) or len(text) > 10:
        raise ValueError(f"{what} {text[:20]!r} is not a non-negative integer")
    return int(text)


def parse_flags(text: bytes) -> frozenset[str]:
    """``b"0"`` -> {}; ``b"ZL"`` -> {"no_pulses", "unlocked"}; ValueError otherwise."""
    return parse_flag_letters(text, FLAG_NAMES)


def parse_status_line(line: bytes, t: float = 0.0, device: str = "", divider: int = 1) -> StrobeStatus:
    """Decode ``S,<seq>,<t_ms>,<f_rot>,<f_strobe>,<phase>,<flags>`` (no LF); ValueError
    naming the bad field."""
    fields = line.strip().split(b",")
    if len(fields) != 7 or fields[0] != b"S":
        raise ValueError(f"not an S line with 7 fields: {line[:48]!r}")
    phase = _decimal(fields[5], "phase_deg", 1)
    if phase >= 360.0:
        raise ValueError(f"phase_deg {phase} not below 360")
    return StrobeStatus(t=t, seq=_integer(fields[1], "seq"), t_ms=_integer(fields[2], "t_ms"),
                        rotor_hz=_decimal(fields[3], "f_rot_hz", 4),
                        strobe_hz=_decimal(fields[4], "f_strobe_hz", 4), phase_deg=phase,
                        flags=parse_flags(fields[6]), raw=line, device=device, divider=divider)


def parse_banner(line: bytes) -> dict[str, str] | None:
    """``# labkit-strobe 1.0 offset=0.500 width=10 div=1 rate=1`` -> {"version": "1.0", ...};
    None for any other line."""
    return parse_sketch_banner(line, "labkit-strobe")


def format_command(name: str, value: float | None = None) -> bytes:
    """``OFFSET 0.5``, ``WIDTH 20``, ``DIV 2``, ``RATE 10``, ``ON``, ``OFF``, ``ID?`` as bytes with
    LF; ValueError for a name or value the strobe would refuse."""
    if name in ("ID?", "ON", "OFF"):
        return f"{name}\n".encode("ascii")
    if name not in COMMANDS or value is None or not math.isfinite(value):
        raise ValueError(f"bad labkit-strobe command {name} {value}")
    low, high = LIMITS[name]
    if not low <= value <= high:
        raise ValueError(f"labkit-strobe {name} {value}: outside {low}..{high}")
    if name == "OFFSET":
        text = f"{value:.4f}".rstrip("0").rstrip(".")
        return f"OFFSET {text}\n".encode("ascii")
    if value != int(value):
        raise ValueError(f"labkit-strobe {name} {value}: must be a whole number")
    return f"{name} {int(value)}\n".encode("ascii")


def strip_junk(line: bytes) -> bytes:
    """Drop bytes before the first known line start (power-on junk, noise on the wire)."""
    return strip_sketch_junk(line, LINE_STARTS)


def width_for_blur(rotor_hz: float, blur_deg: float) -> float:
    """Flash width (us) that smears a point of the rotor over ``blur_deg``: the angle swept
    in the flash is 2 pi f_rot w, so w = blur / (360 f_rot) (docs/reference/devices-strobe.md)."""
    if rotor_hz <= 0 or blur_deg <= 0:
        raise ValueError("rotor frequency and blur must be positive")
    return blur_deg / (360.0 * rotor_hz) * 1e6
