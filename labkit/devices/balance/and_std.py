"""A&D standard format (EK-i, FX-i/FZ-i, GX/GF, EJ, GC;
docs/reference/devices-balance.md#and_std-ad-standard-format): parse/format + driver.

Data lines are 17 bytes: ``ST,+00012.34  g`` CR LF (``ST`` stable, ``US`` unstable, ``QT``
count, ``OL`` out of range with *filler* digits that are never a reading). The manuals' own
overload line is ``OL,+9999999E+19`` (``OL,-9999999E+19`` below the range): 15 characters
like a data line, no unit field. The unit can be
``  N``: the balance then measures force directly. Control commands are acknowledged with
ACK (0x06, twice for ``R``/``Z``/``T``: on receipt and on completion) when the balance's
``erCd`` menu setting is 1; errors come as ``EC,Exx``. Factory serial settings: 2400 7E1.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import serial

from labkit.devices.balance.continuous import ContinuousMixin
from labkit.devices.base import Balance
from labkit.devices.link import FrameError, LineLink, LinkTailMixin, eol_bytes
from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.errors import DeviceReplyError
from labkit.io.clock import Clock
from labkit.readings import Reading
from labkit.units import UnitError, to_si

ACK = b"\x06"

ERROR_CODES = {
    "E00": "communication error (EC,E00): check baud rate/parity (A&D default 2400 7E1)",
    "E01": "undefined command (EC,E01)",
    "E02": "balance not ready (EC,E02)",
    "E03": "command timeout (EC,E03): command bytes arrived too slowly",
    "E04": "excess characters (EC,E04)",
    "E06": "format error (EC,E06)",
    "E07": "parameter out of range (EC,E07)",
    "E11": "stability error (EC,E11): the weight did not settle",
    "E17": "out of range (EC,E17)",
    "E20": "calibration weight too heavy (EC,E20)",
    "E21": "calibration weight too light (EC,E21)",
}

_DATA = re.compile(r"(ST|US|QT|OL),(?:(LO|OK|HI|--),)?([+-])([0-9.]{8})([ A-Za-z%]{3})\Z")
_OVERLOAD_E19 = re.compile(r"OL,[+-]9999999E\+19\Z")
_DIGITS = re.compile(r"\d*\.?\d*\Z")
_ERROR = re.compile(r"EC,(E\d\d)\Z")
_INFO = re.compile(r"(ID|SN|TN),([ -~]*)\Z")


#: the overload lines the manuals give (above and below the range)
OVERLOAD_LINE = b"OL,+9999999E+19\r\n"
UNDERLOAD_LINE = b"OL,-9999999E+19\r\n"


@dataclass(frozen=True)
class AndData:
    """A data line. ``value`` is None for ``OL`` (its digits are a filler)."""

    header: str
    value: float | None
    unit: str
    comparator: str | None = None

    @property
    def stable(self) -> bool:
        return self.header in ("ST", "QT")

    @property
    def overload(self) -> bool:
        return self.header == "OL"


@dataclass(frozen=True)
class AndError:
    code: str  # "E00".."E99"

    @property
    def meaning(self) -> str:
        return ERROR_CODES.get(self.code, f"error code EC,{self.code}")


@dataclass(frozen=True)
class AndInfo:
    key: str    # ID, SN, TN
    value: str


@dataclass(frozen=True)
class AndAck:
    pass


AndLine = AndData | AndError | AndInfo | AndAck


def parse_line(line: bytes) -> AndLine:
    """Classify one A&D output line (terminator optional). Raises FrameError on garbage."""
    line = line.rstrip(b"\r\n")
    if line == ACK:
        return AndAck()
    if not line or any(b < 0x20 or b > 0x7E for b in line):
        raise FrameError(f"not a printable ASCII line: {line!r}")
    text = line.decode("ascii")
    if _OVERLOAD_E19.match(text):
        return AndData("OL", None, "")
    m = _DATA.match(text)
    if m:
        header, comparator, sign, digits, unit_field = m.groups()
        unit = unit_field.strip()
        if not unit or " " in unit or unit_field != unit.rjust(3):
            raise FrameError(f"bad unit field in {line!r}")
        if header == "OL":
            return AndData(header, None, unit, comparator)
        if not _DIGITS.match(digits) or not any(c.isdigit() for c in digits):
            raise FrameError(f"bad number in {line!r}")
        value = float(digits)
        return AndData(header, -value if sign == "-" else value, unit, comparator)
    m = _ERROR.match(text)
    if m:
        return AndError(m.group(1))
    m = _INFO.match(text)
    if m:
        return AndInfo(m.group(1), m.group(2).strip())
    raise FrameError(f"not an A&D line: {line!r}")


def format_data(header: str, value: float | None, unit: str = "g", decimals: int = 2) -> bytes:
    """Format a 17-byte data line; ``OL`` gets the ``+999999.9`` filler (the manuals' own
    overload line is :data:`OVERLOAD_LINE`)."""
    if header == "OL" or value is None:
        body = "+999999.9" if (value is None or value >= 0) else "-999999.9"
        return f"OL,{body}{unit:>3}".encode("ascii") + b"\r\n"
    digits = f"{abs(value):0{8}.{decimals}f}"
    if len(digits) != 8:
        raise ValueError(f"{value} does not fit the 8-character A&D field with {decimals} decimals")
    sign = "-" if value < 0 and float(digits) != 0.0 else "+"
    return f"{header},{sign}{digits}{unit:>3}".encode("ascii") + b"\r\n"


def format_error(code: str) -> bytes:
    return f"EC,{code}".encode("ascii") + b"\r\n"


def format_command(command: str, eol: bytes = b"\r\n") -> bytes:
    return command.encode("ascii") + eol


register_parser_benchmark("and_std", b"ST,+00012.34  g\r\n", parse_line)


@register_driver
class AndStdBalance(ContinuousMixin, LinkTailMixin, Balance):
    """A&D balance in command mode (default) or stream mode.

    Options: ``eol`` (``"CRLF"``/``"CR"``, the balance's command terminator), ``ack``
    (True: ``erCd`` = 1, control commands are acknowledged; False: nothing comes back and
    zero/tare wait ``settle_s``), ``mode`` (``"command"`` or ``"stream"`` for a balance
    set to stream output), ``command_timeout_s`` (2), ``settle_s`` (3).
    On open (command mode): flush, send ``C`` (cancel ``S``/``SIR``;
    docs/explanation/device-rules.md#driver-rules).
    ``start_continuous()`` sends ``SIR`` (command mode) and reads the stream on a reader;
    ``stop_continuous()`` sends ``C``.
    """

    protocol = "and_std"
    option_names = frozenset({"ack", "command_timeout_s", "eol", "mode", "settle_s"})
    default_serial = {"baudrate": 2400, "bytesize": 7, "parity": "E", "stopbits": 1}

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        eol = eol_bytes(str(options.get("eol", "CRLF")))
        self.ack = str(options.get("ack", True)).lower() not in ("false", "0", "no")
        self.mode = str(options.get("mode", "command"))
        if self.mode not in ("command", "stream"):
            raise ValueError(f"mode {self.mode!r}: expected 'command' or 'stream'")
        self.command_timeout = float(options.get("command_timeout_s", 2.0))
        self.settle_s = float(options.get("settle_s", 3.0))
        self.link = LineLink(port, clock, self.name, expected_serial=self.default_serial,
                             write_eol=eol, read_eol=b"\n", single_bytes=ACK)
        self._last_quantity = ("mass", "kg")
        self.link.discard_stale("C")
        try:
            port.reset_input_buffer()
        except (serial.SerialException, OSError):
            pass
        if self.mode == "command":
            self._control("C", acks=1, timeout=self.command_timeout)

    # ---- helpers ----------------------------------------------------------------------
    def _accept(self, command: str, want: type):
        def accept(line: bytes) -> AndLine | None:
            parsed = parse_line(line)
            if isinstance(parsed, AndError):
                raise DeviceReplyError(self.name, command, self.link.last_bytes, parsed.meaning)
            return parsed if isinstance(parsed, want) else None

        return accept

    def _ask(self, command: str | None, want: type, timeout: float,
             retry_after: float | None = None) -> tuple[float, bytes, Any]:
        """Send ``command`` and wait for a line of type ``want``; resend once after E00."""
        label = command or "stream"
        try:
            return self.link.exchange(command, self._accept(label, want), timeout, retry_after)
        except DeviceReplyError as exc:
            if command is None or exc.reason != ERROR_CODES["E00"]:
                raise
            return self.link.exchange(command, self._accept(label, want), timeout, retry_after)

    def _control(self, command: str, acks: int, timeout: float) -> None:
        if not self.ack:
            self.link.discard_stale(command)
            self.link.send(command)
            return
        self._ask(command, AndAck, min(timeout, self.command_timeout))
        for _ in range(acks - 1):  # completion ACK (R/Z/T wait for stability)
            self.link.exchange(None, self._accept(command, AndAck), timeout)

    def _reading(self, t: float, line: bytes, data: AndData, command: str) -> Reading:
        if data.overload:
            quantity, unit = self._last_quantity
            return Reading(t, quantity, float("nan"), unit, stable=False, overload=True,
                           raw=line, device=self.name, flags=frozenset({"overload"}))
        assert data.value is not None
        try:
            quantity, value, unit = to_si(data.value, data.unit)
        except UnitError as exc:
            raise DeviceReplyError(self.name, command, line, str(exc)) from None
        self._last_quantity = (quantity, unit)
        flags = frozenset({f"comparator_{data.comparator}"}) if data.comparator else frozenset()
        return Reading(t, quantity, value, unit, stable=data.stable, overload=False, raw=line,
                       device=self.name, flags=flags)

    # ---- continuous output (SIR / stream mode) ----------------------------------------
    def _begin_stream(self) -> None:
        if self.mode == "command":
            self.link.discard_stale("SIR")
            self.link.send("SIR")

    def _end_stream(self) -> None:
        if self.mode == "command":
            self._control("C", acks=1, timeout=self.command_timeout)

    def _stream_reading(self, t: float, line: bytes) -> Reading | None:
        parsed = parse_line(line)
        if isinstance(parsed, AndError):
            raise DeviceReplyError(self.name, "SIR", line, parsed.meaning)
        if isinstance(parsed, AndData):
            return self._reading(t, line, parsed, "SIR")
        return None

    # ---- public -----------------------------------------------------------------------
    def identify(self) -> dict[str, Any]:
        """``?ID``, ``?SN``, ``?TN`` (a model without one answers EC,E01: left out)."""
        info: dict[str, Any] = {"protocol": self.protocol}
        if self.mode == "stream":
            return info
        with self.paused():
            return self._identify(info)

    def _identify(self, info: dict[str, Any]) -> dict[str, Any]:
        names = {"?ID": "id", "?SN": "serial", "?TN": "model"}
        for command, key in names.items():
            try:
                _, _, parsed = self._ask(command, AndInfo, self.command_timeout, retry_after=0.5)
            except DeviceReplyError as exc:
                if exc.reason == ERROR_CODES["E01"]:
                    continue
                raise
            info[key] = parsed.value
        return info

    def read(self, timeout: float = 2.0) -> Reading:
        """``Q``: the weight now (stream mode or continuous: the next data line)."""
        if self.stream is not None:
            return self.stream.wait_new(self.clock.now(), timeout)
        if self.mode == "stream":
            t, line, data = self._ask(None, AndData, timeout)
            return self._reading(t, line, data, "stream")
        t, line, data = self._ask("Q", AndData, timeout, retry_after=min(0.7, timeout / 2))
        return self._reading(t, line, data, "Q")

    def read_stable(self, timeout: float = 20.0) -> Reading:
        """``S``: the balance answers once the weight is stable (EC,E11 if it does not settle)."""
        if self.mode == "stream" or self.stream is not None:
            return super().read_stable(timeout)
        t, line, data = self._ask("S", AndData, timeout)
        return self._reading(t, line, data, "S")

    def zero(self, timeout: float = 20.0) -> None:
        """``Z`` (re-zero): waits for both ACKs (receipt, completion) when ``ack`` is on."""
        with self.paused():
            self._control("Z", acks=2, timeout=timeout)
            if not self.ack:
                self.clock.sleep(self.settle_s)

    def tare(self, timeout: float = 20.0) -> None:
        """``T``: tare, acknowledged like ``Z``."""
        with self.paused():
            self._control("T", acks=2, timeout=timeout)
            if not self.ack:
                self.clock.sleep(self.settle_s)
