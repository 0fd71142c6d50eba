"""Mettler Toledo MT-SICS (docs/reference/devices-balance.md#mtsics-mettler-toledo-mt-sics): pure parse/format
functions + the driver.

Also the protocol of the labkit HX711 sketch (MT-SICS level-0 subset), so one driver
covers Mettler balances and DIY load cells. Lines: ``ID Status Fields CR LF``; weight
replies ``S S     12.34 g`` (stable) / ``S D ...`` (dynamic); ``S +`` / ``S -`` over/under
load carry no number; ``ES``/``ET``/``EL`` are general errors.
"""

from __future__ import annotations

import math
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

GENERAL_ERRORS = {
    "ES": "syntax error: the balance does not know this command (ES)",
    "ET": "transmission error (ET): check baud rate/parity and cable",
    "EL": "logical error: the balance cannot execute this command now (EL)",
}
STATUS_MEANING = {
    "I": "busy or no stable value within the balance's timeout (I)",
    "L": "logical error or bad parameter (L)",
    "+": "overload: above the upper limit (+)",
    "-": "underload: below the lower limit (-)",
}

_ID = re.compile(r"[A-Z][A-Z0-9]*\Z")
_STATUS = frozenset("SDABIL+-")
_NUMBER = re.compile(r"-?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d{1,3})?\Z")
_TOKEN = re.compile(r'"[^"]*"|[^ "]+')


@dataclass(frozen=True)
class MtReply:
    """One parsed MT-SICS line. ``command`` is the echoed ID (``""`` for ES/ET/EL)."""

    command: str
    status: str
    fields: tuple[str, ...] = ()

    @property
    def is_general_error(self) -> bool:
        return self.command == ""


@dataclass(frozen=True)
class MtWeight:
    """A weight line. ``value`` is None for ``+``/``-``/``I`` (never a number then)."""

    command: str
    status: str          # S stable, D dynamic, + overload, - underload, I busy
    value: float | None
    unit: str | None

    @property
    def stable(self) -> bool:
        return self.status == "S"

    @property
    def overload(self) -> bool:
        return self.status in "+-"


def format_command(command: str, *params: str) -> bytes:
    """``format_command("SI") == b"SI\\r\\n"``; parameters are joined by one space."""
    return " ".join((command, *params)).encode("ascii") + b"\r\n"


def _decode(line: bytes) -> str:
    line = line.rstrip(b"\r\n")
    if not line or any(b < 0x20 or b > 0x7E for b in line):
        raise FrameError(f"not a printable ASCII line: {line!r}")
    return line.decode("ascii")


def parse_reply(line: bytes) -> MtReply:
    """Parse any MT-SICS reply line (terminator optional). Raises FrameError on garbage."""
    text = _decode(line)
    if text in GENERAL_ERRORS:
        return MtReply("", text)
    tokens = _TOKEN.findall(text)
    if "".join(tokens).replace(" ", "") != text.replace(" ", ""):
        raise FrameError(f"unbalanced quotes: {line!r}")
    if len(tokens) < 2 or not _ID.match(tokens[0]) or tokens[1] not in _STATUS:
        raise FrameError(f"not an MT-SICS reply: {line!r}")
    fields = tuple(tok[1:-1] if tok.startswith('"') else tok for tok in tokens[2:])
    return MtReply(tokens[0], tokens[1], fields)


def parse_weight(line: bytes) -> MtWeight:
    """Parse a weight reply (``S``, ``SI``, ``SIR``, ``T``, ``TA``: ``ID Status Value Unit``).

    ``S``/``D`` need exactly a number and a unit; ``+``/``-``/``I``/``L`` must carry no
    value. Anything else raises FrameError, so garbage never becomes a reading.
    """
    reply = parse_reply(line)
    if reply.is_general_error:
        raise FrameError(f"general error, not a weight: {line!r}")
    if reply.status in ("S", "D", "A"):
        if len(reply.fields) != 2 or not _NUMBER.match(reply.fields[0]):
            raise FrameError(f"weight field is not a number and a unit: {line!r}")
        unit = reply.fields[1]
        if not unit.isalnum() and unit != "%":
            raise FrameError(f"bad unit in {line!r}")
        value = float(reply.fields[0])
        if not math.isfinite(value):
            raise FrameError(f"weight out of range: {line!r}")
        status = "S" if reply.status == "A" else reply.status
        return MtWeight(reply.command, status, value, unit)
    if reply.status in ("+", "-", "I", "L") and not reply.fields:
        return MtWeight(reply.command, reply.status, None, None)
    raise FrameError(f"not a weight reply: {line!r}")


def format_weight(command: str, status: str, value: float | None, unit: str = "g",
                  decimals: int = 2) -> bytes:
    """Format a weight reply: value right-aligned in 10 characters
    (docs/reference/devices-balance.md#mtsics-mettler-toledo-mt-sics)."""
    if value is None or status in "+-IL":
        return f"{command} {status}".encode("ascii") + b"\r\n"
    return f"{command} {status} {value:>10.{decimals}f} {unit}".encode("ascii") + b"\r\n"


def parse_quoted_info(reply: MtReply) -> str:
    """The quoted text of an ``I2``/``I4`` reply (empty string if none)."""
    return " ".join(reply.fields)


def parse_i2(text: str) -> dict[str, Any]:
    """``"XS205 220.00 g"`` -> model, capacity and unit (type may contain spaces: parse
    from the right)."""
    parts = text.split()
    if len(parts) >= 3 and _NUMBER.match(parts[-2]):
        return {"model": " ".join(parts[:-2]), "capacity": float(parts[-2]), "capacity_unit": parts[-1]}
    return {"model": text}


register_parser_benchmark("mtsics", b"S S      12.34 g\r\n", parse_weight)


@register_driver
class MtSicsBalance(ContinuousMixin, LinkTailMixin, Balance):
    """MT-SICS balance (Mettler Toledo, labkit HX711 sketch).

    Options (rig file ``[devices.balance.options]``): ``eol`` (``"CRLF"`` default, ``"CR"``,
    ``"LF"``), ``command_timeout_s`` (2, for immediate commands).
    On open: flush input, send ``@`` (reset to a known state, cancels ``SIR``), wait for
    the ``I4`` reply (docs/explanation/device-rules.md#driver-rules, rule 3). ``start_continuous()`` sends
    ``SIR`` and reads
    the stream on a reader (``latest()``, ``readings_since(t)``); ``stop_continuous()``
    sends ``@``.
    """

    protocol = "mtsics"
    option_names = frozenset({"command_timeout_s", "eol"})
    default_serial = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        eol = eol_bytes(str(options.get("eol", "CRLF")))
        self.command_timeout = float(options.get("command_timeout_s", 2.0))
        self.read_eol = b"\r" if eol == b"\r" else b"\n"
        self.link = LineLink(
            port, clock, self.name, expected_serial=self.default_serial,
            write_eol=eol, read_eol=self.read_eol,
            on_unsolicited=self._unsolicited,
        )
        self.serial_number = ""
        self.resets_seen = 0
        self._reset_pending = False
        self._last_quantity = ("mass", "kg")  # for overload readings, which carry no unit
        self.link.discard_stale("@")
        try:
            port.reset_input_buffer()
        except (serial.SerialException, OSError):
            pass  # a dead port shows itself on the next real I/O, with a proper message
        self.reset()
        self.resets_seen = 0  # the power-on banner before our @ is not a reset during use

    # ---- helpers ----------------------------------------------------------------------
    def _unsolicited(self, t: float, line: bytes) -> None:
        # the power-on / reset banner, maybe behind power-on junk: tare and zero are gone
        at = line.find(b'I4 A "')
        if at == 0 or (at > 0 and any(b < 0x20 or b > 0x7E for b in line[:at])):
            self.resets_seen += 1
            self._reset_pending = True

    def _accept(self, command: str, reply_id: str):
        def accept(line: bytes) -> MtReply | None:
            try:
                reply = parse_reply(line)
            except FrameError:
                self._unsolicited(0.0, line)
                raise
            if reply.is_general_error:
                raise DeviceReplyError(self.name, command, self.link.last_bytes, GENERAL_ERRORS[reply.status])
            return reply if reply.command == reply_id else None

        return accept

    def command(self, command: str, reply_id: str, timeout: float,
                 retry_after: float | None = None) -> tuple[float, bytes, MtReply]:
        """Send, wait for the reply with ``reply_id``; one resend after an ``ET``."""
        try:
            return self.link.exchange(command, self._accept(command, reply_id), timeout, retry_after)
        except DeviceReplyError as exc:
            if exc.reason != GENERAL_ERRORS["ET"]:
                raise
            return self.link.exchange(command, self._accept(command, reply_id), timeout, retry_after)

    def _fail(self, command: str, line: bytes, reply: MtReply) -> DeviceReplyError:
        meaning = STATUS_MEANING.get(reply.status, f"status {reply.status}")
        return DeviceReplyError(self.name, command, self.link.last_bytes, meaning)

    def _reading(self, t: float, line: bytes, command: str) -> Reading:
        try:
            weight = parse_weight(line)
        except FrameError as exc:
            raise DeviceReplyError(self.name, command, line, f"unreadable weight reply ({exc})") from None
        flags = {"device_reset"} if self._reset_pending else set()
        self._reset_pending = False
        if weight.status in ("I", "L"):
            raise DeviceReplyError(self.name, command, self.link.last_bytes, STATUS_MEANING[weight.status])
        if weight.overload:
            flags.add("overload" if weight.status == "+" else "underload")
            quantity, unit = self._last_quantity
            return Reading(t, quantity, float("nan"), unit, stable=False, overload=True, raw=line,
                           device=self.name, flags=frozenset(flags))
        assert weight.value is not None and weight.unit is not None
        try:
            quantity, value, unit = to_si(weight.value, weight.unit)
        except UnitError as exc:
            raise DeviceReplyError(self.name, command, line, str(exc)) from None
        self._last_quantity = (quantity, unit)
        return Reading(t, quantity, value, unit, stable=weight.stable, overload=False, raw=line,
                       device=self.name, flags=frozenset(flags))

    # ---- continuous output (SIR) ------------------------------------------------------
    def _begin_stream(self) -> None:
        self.link.discard_stale("SIR")
        self.link.send("SIR")

    def _end_stream(self) -> None:
        self.reset()  # @ cancels SIR

    def _stream_reading(self, t: float, line: bytes) -> Reading | None:
        try:
            reply = parse_reply(line)
        except FrameError:
            self._unsolicited(t, line)
            raise
        if reply.command == "S" and reply.status in "SD+-":
            return self._reading(t, line, "SIR")
        self._unsolicited(t, line)
        return None

    # ---- public -----------------------------------------------------------------------
    def reset(self) -> str:
        """``@``: reset to the power-on state (no zeroing), cancel ``SIR``; returns serial no."""
        _, _, reply = self.command("@", "I4", self.command_timeout, retry_after=0.5)
        self.serial_number = parse_quoted_info(reply)
        self._reset_pending = False
        return self.serial_number

    def identify(self) -> dict[str, Any]:
        """``I2`` (type, capacity, unit) and ``I4`` (serial number)."""
        with self.paused():
            return self._identify()

    def _identify(self) -> dict[str, Any]:
        _, line, reply = self.command("I2", "I2", self.command_timeout, retry_after=0.5)
        if reply.status != "A":
            raise self._fail("I2", line, reply)
        info: dict[str, Any] = {"protocol": self.protocol}
        info.update(parse_i2(parse_quoted_info(reply)))
        _, line, reply = self.command("I4", "I4", self.command_timeout, retry_after=0.5)
        if reply.status == "A":
            info["serial"] = parse_quoted_info(reply)
        return info

    def read(self, timeout: float = 2.0) -> Reading:
        """``SI``: the weight now, stable (``S S``) or not (``S D``); overload -> flagged, NaN.
        While continuous: the next streamed reading."""
        if self.stream is not None:
            return self.stream.wait_new(self.clock.now(), timeout)
        t, line, _ = self.command("SI", "S", timeout, retry_after=min(0.5, timeout / 2))
        return self._reading(t, line, "SI")

    def read_stable(self, timeout: float = 20.0) -> Reading:
        """``S``: the balance waits for stability; ``S I`` (its own timeout) raises.
        While continuous: the next stable streamed reading."""
        if self.stream is not None:
            return super().read_stable(timeout)
        t, line, _ = self.command("S", "S", timeout)
        reading = self._reading(t, line, "S")
        return reading

    def zero(self, timeout: float = 20.0) -> None:
        """``Z``: zero when stable. ``Z I`` (not stable), ``Z +``/``Z -`` (out of range) raise."""
        with self.paused():
            _, line, reply = self.command("Z", "Z", timeout)
        if reply.status != "A":
            raise self._fail("Z", line, reply)

    def tare(self, timeout: float = 20.0) -> Reading:  # type: ignore[override]
        """``T``: tare when stable; returns the tare weight as a Reading."""
        with self.paused():
            t, line, reply = self.command("T", "T", timeout)
        if reply.status not in ("S", "A"):
            raise self._fail("T", line, reply)
        return self._reading(t, line, "T")

    def tare_value(self, timeout: float = 2.0) -> Reading:
        """``TA``: the stored tare weight."""
        with self.paused():
            t, line, reply = self.command("TA", "TA", timeout, retry_after=0.5)
        if reply.status != "A":
            raise self._fail("TA", line, reply)
        return self._reading(t, line, "TA")

    def clear_tare(self, timeout: float = 2.0) -> None:
        """``TAC``: clear the tare."""
        with self.paused():
            _, line, reply = self.command("TAC", "TAC", timeout, retry_after=0.5)
        if reply.status != "A":
            raise self._fail("TAC", line, reply)
