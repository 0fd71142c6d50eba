"""Validation helpers of rig files (:mod:`labkit.rig`): unit suffixes, absolute sanity caps,
role names, bounded reading, and :class:`TableSection`, which reads one TOML table.

Imports no device code except to check an emulated port URL. Caps and role names are
documented in docs/reference/rig-files.md ("Finite values and caps", ``[devices.ROLE]``).
"""

from __future__ import annotations

import difflib
import math
import os
import re
import stat
from pathlib import Path
from typing import Any, overload

from labkit.errors import RigFileError
from labkit.units import RAD_S_PER_RPM
from labkit.units import UNIT_SUFFIXES as _UNIT_SUFFIXES

#: key suffix -> (SI unit, factor to SI): the one table, in labkit/units.py
UNIT_SUFFIXES = _UNIT_SUFFIXES

#: Absolute sanity caps, whatever a rig file says (docs/reference/rig-files.md, "Caps"). A value beyond
#: one is a typo or a unit mistake, never a setting: the fastest rotor of the paper turns at
#: 100 000 RPM, and an interlock that waits an hour is no interlock.
MAX_SPEED_RPM = 150_000.0             # every speed (limits, control, ...)
MAX_RAMP_RPM_PER_S = 150_000.0        # every acceleration
MAX_DURATION_S = 3600.0               # every time: settle timeouts, serial timeouts, ...
MAX_TACH_TIMEOUT_S = 10.0             # tachometer silent longer than this cannot be allowed
MAX_CONTROL_PERIOD_S = 1.0            # a speed loop slower than 1 Hz cannot hold a ramp
MAX_RIG_FILE_BYTES = 1_000_000        # a rig file is a few kB; /dev/zero is not a rig file
MIN_CONTROL_PERIOD_S = 1e-3           # control.period / status_period: no serial device answers faster
#: a rate (``rate_hz`` of a driver option or a sim:// URL): the fastest device streams 200 lines/s
#: (labkit_tach RATE 1..200); 1 kHz leaves room and bounds the work of an emulated second
MAX_RATE_HZ = 1000.0
#: dotted parts of one TOML key (``a.b.c``): a rig file nests three deep; tomllib takes
#: quadratic time in the parts (60 000 parts: over a minute), so a bound is read first
MAX_KEY_PARTS = 32
#: Device roles and loop names become file names inside a session (``readings/ROLE.jsonl``).
ROLE_PATTERN = re.compile(r"[a-z][a-z0-9_]{0,63}")
_CAPS_SI: dict[str, tuple[float, str]] = {
    "rad/s": (MAX_SPEED_RPM * RAD_S_PER_RPM, f"{MAX_SPEED_RPM:.0f} RPM"),
    "rad/s^2": (MAX_RAMP_RPM_PER_S * RAD_S_PER_RPM, f"{MAX_RAMP_RPM_PER_S:.0f} RPM/s"),
    "s": (MAX_DURATION_S, f"{MAX_DURATION_S:.0f} s"),
}

def split_unit(key: str) -> tuple[str, str, float] | None:
    """``"mass_g"`` -> ``("mass", "kg", 1e-3)``; None when the key has no unit suffix."""
    lowered = key.lower()
    for suffix in sorted(UNIT_SUFFIXES, key=len, reverse=True):
        if lowered.endswith("_" + suffix):
            unit, factor = UNIT_SUFFIXES[suffix]
            return key[: -len(suffix) - 1], unit, factor
    return None


class TableSection:
    """Reads one TOML table, converting unit suffixes and remembering unknown keys."""

    def __init__(self, file: str, prefix: str, table: Any) -> None:
        self.file, self.prefix = file, prefix
        if not isinstance(table, dict):
            raise RigFileError(file, prefix, f"must be a table, got {type(table).__name__}")
        self.table = dict(table)
        self.used: set[str] = set()
        #: every key this section was asked for (raw names; quantities as base_suffix), for "did you mean"
        self.asked: set[str] = set()
        self.asked_bases: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.prefix}.{name}" if self.prefix else name

    def error(self, key: str, reason: str) -> RigFileError:
        return RigFileError(self.file, self.key(key), reason)

    def raw(self, name: str, typ: type | tuple[type, ...], required: bool = False,
            default: Any = None) -> Any:
        self.asked.add(name)
        if name not in self.table:
            if required:
                raise self.error(name, "missing (required)" + self._given_instead(name))
            return default
        self.used.add(name)
        value = self.table[name]
        ok = isinstance(value, typ) and not (isinstance(value, bool) and typ in (int, float, (int, float)))
        if not ok:
            want = typ.__name__ if isinstance(typ, type) else " or ".join(t.__name__ for t in typ)
            raise self.error(name, f"must be {want}, got {value!r}")
        if isinstance(value, float) and not math.isfinite(value):
            raise self.error(name, f"must be a finite number, got {value!r}")
        return value

    @overload
    def quantity(self, base: str, si_unit: str, required: bool = False, *, default: float,
                 positive: bool = True, allow_zero: bool = False,
                 cap: tuple[float, str] | None = None) -> float: ...

    @overload
    def quantity(self, base: str, si_unit: str, required: bool = False, default: None = None,
                 positive: bool = True, allow_zero: bool = False,
                 cap: tuple[float, str] | None = None) -> float | None: ...

    def quantity(self, base: str, si_unit: str, required: bool = False, default: float | None = None,
                 positive: bool = True, allow_zero: bool = False,
                 cap: tuple[float, str] | None = None) -> float | None:
        """Find ``base_<suffix>`` with a suffix of ``si_unit``; return the SI value.

        The value must be finite and at most ``cap`` (SI value, text), by default the
        absolute cap of its unit (:data:`MAX_SPEED_RPM`, :data:`MAX_DURATION_S`, ...)."""
        self.asked.add(f"{base}_{_example_suffix(si_unit)}")
        self.asked_bases.add(base)
        found = [k for k in self.table if (s := split_unit(k)) and s[0] == base]
        if len(found) > 1:
            raise self.error(found[1], f"given twice (also as {found[0]})")
        if not found:
            if base in self.table:
                raise self.error(base, f"needs a unit suffix, e.g. {base}_{_example_suffix(si_unit)}")
            if required:
                example = f"{base}_{_example_suffix(si_unit)}"
                raise self.error(example, "missing (required)" + self._given_instead(example, base))
            return default
        key = found[0]
        _, unit, factor = split_unit(key)  # type: ignore[misc]
        self.used.add(key)
        if unit != si_unit:
            raise self.error(key, f"wrong unit: {base} is a {si_unit} quantity")
        value = self.table[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(key, f"must be a number, got {value!r}")
        if not math.isfinite(value):
            raise self.error(key, f"must be a finite number, got {value!r}")
        if positive and (value < 0 or (value == 0 and not allow_zero)):
            raise self.error(key, f"must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
        si = float(value) * factor
        limit = cap if cap is not None else _CAPS_SI.get(si_unit)
        if limit is not None and abs(si) > limit[0] * (1 + 1e-12):
            raise self.error(key, f"{value!r} is beyond the sanity cap of {limit[1]}")
        return si

    def _given_instead(self, name: str, base: str | None = None) -> str:
        """``; did you mean ...`` when the table holds an unread key close to ``name``."""
        unread = [k for k in self.table if k not in self.used]
        close = difflib.get_close_matches(name, unread, n=1, cutoff=0.6)
        if not close and base is not None:  # a quantity: compare without the unit suffix
            stems = {(s[0] if (s := split_unit(k)) else k): k for k in unread}
            close = [stems[m] for m in difflib.get_close_matches(base, list(stems), n=1, cutoff=0.6)]
        return f"; the file has {close[0]!r}: did you mean {name!r}?" if close else ""

    def _suggestion(self, key: str) -> str:
        """``; did you mean 'KEY'?`` for an unknown key close to one this section reads."""
        close = difflib.get_close_matches(key, sorted(self.asked - self.used), n=1, cutoff=0.6)
        if not close and (split := split_unit(key)):  # max_sped_rpm -> max_speed_rpm
            bases = difflib.get_close_matches(split[0], sorted(self.asked_bases), n=1, cutoff=0.6)
            close = [key.replace(split[0], bases[0], 1)] if bases else []
        return f"; did you mean {close[0]!r}?" if close else ""

    def finish(self) -> None:
        for k in self.table:
            if k not in self.used:
                raise self.error(k, "unknown key" + self._suggestion(k))


def _example_suffix(si_unit: str) -> str:
    return {"rad/s": "rpm", "rad/s^2": "rpm_per_s", "kg": "g", "m": "mm", "rad": "deg",
            "s": "s", "kg m^2": "kg_m2", "A m^2": "a_m2", "N": "n"}.get(si_unit, "si")


def check_finite(sec: TableSection, key: str, value: Any) -> None:
    """Every number inside ``value`` (a driver's options, nested) is finite: a NaN timeout or
    gain handed to a driver is a wait that never ends or a duty that means full power."""
    if isinstance(value, float) and not math.isfinite(value):
        raise sec.error(key, f"must be a finite number, got {value!r}")
    if isinstance(value, dict):
        for k, v in value.items():
            check_finite(sec, f"{key}.{k}", v)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            check_finite(sec, f"{key}[{i}]", v)


def check_role(file: str, key: str, role: str) -> None:
    """A device role or loop name is ``[a-z][a-z0-9_]*`` (at most 64 characters): it becomes
    a file name inside a session, so ``../x`` or ``/tmp/x`` would write outside it."""
    if not ROLE_PATTERN.fullmatch(role):
        raise RigFileError(file, key, f"name {role!r} must be lower-case letters, digits and _, "
                                      "starting with a letter (at most 64 characters)")


def rate_problem(name: str, value: Any) -> str | None:
    """Why an option ``name`` ending in ``_hz`` cannot be ``value`` (None: it can, or it is no
    rate). A rate of -5 or 1e9 Hz makes an emulator or a device stream for ever."""
    if not name.lower().endswith("_hz"):
        return None
    try:
        rate = float(value)
    except (TypeError, ValueError):
        return None  # not a number: the driver or emulator names it
    if isinstance(value, bool) or not (math.isfinite(rate) and 0 < rate <= MAX_RATE_HZ):
        return f"a rate must be in (0, {MAX_RATE_HZ:g}] Hz, got {value!r}"
    return None


def check_rate_options(sec: TableSection, key: str, options: dict[str, Any]) -> None:
    """Every ``*_hz`` driver option is a rate in (0, :data:`MAX_RATE_HZ`]."""
    for name, value in options.items():
        problem = rate_problem(name, value)
        if problem is not None:
            raise sec.error(f"{key}.{name}", problem)


def check_toml_shape(text: str, file: str) -> None:
    """Refuse, before tomllib reads it, a key with more than :data:`MAX_KEY_PARTS` dotted
    parts (a header ``[a.b.c]`` or the key before a line's first ``=``)."""
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.lstrip()
        if not stripped or stripped.startswith("#"):
            continue
        if stripped.startswith("["):
            key = stripped.split("]", 1)[0]
        elif "=" in stripped:
            key = stripped.split("=", 1)[0]
        else:
            continue
        parts = key.count(".") + 1
        if parts > MAX_KEY_PARTS:
            raise RigFileError(file, f"(line {number})",
                               f"a key of {parts} dotted parts; a rig file nests at most "
                               f"{MAX_KEY_PARTS} deep")


def read_rig_text(path: Path) -> str:
    """A rig file's text, read with a bound (:data:`MAX_RIG_FILE_BYTES`). RigFileError otherwise.

    Only a regular file is read: a FIFO would wait for a writer for ever, a device (``/dev/zero``)
    never ends. The file is opened without blocking and checked before a byte is read."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise RigFileError(str(path), "(file)", f"cannot read: {exc.strerror or exc}") from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a directory" if stat.S_ISDIR(mode)
                    else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "a socket")
            raise RigFileError(str(path), "(file)", f"is {kind}, not a regular file; not a rig file")
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read(MAX_RIG_FILE_BYTES + 1)
    except OSError as exc:
        raise RigFileError(str(path), "(file)", f"cannot read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if len(data) > MAX_RIG_FILE_BYTES:
        raise RigFileError(str(path), "(file)",
                           f"larger than {MAX_RIG_FILE_BYTES // 1000} kB; not a rig file")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise RigFileError(str(path), "(file)", f"not UTF-8 text (byte {exc.start})") from None
