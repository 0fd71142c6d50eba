"""VESC UART packets (docs/reference/devices-tach-motor.md#vesc-vesc-uart-packets): BLDC controllers with
closed-loop ERPM.

Framing: ``02 LEN payload CRChi CRClo 03`` (payload <= 255 bytes), ``03 LENhi LENlo ...``
for longer payloads. The CRC is CRC-16/XMODEM (poly 0x1021, init 0) over the payload,
big-endian. A receiver that sees a bad length, stop byte or CRC discards one byte and
scans again, silently, exactly as the firmware does. Payload byte 0 is the command ID;
fields are big-endian fixed point. Set commands get no reply and each one resets the
controller's 1 s communication timeout, which releases the motor when we fall silent.

Speeds are electrical: ERPM = mechanical RPM x pole pairs, so a 100 000 RPM rig needs a
1-pole-pair motor or a raised ERPM limit.

GET_VALUES replies are decoded in the layout of the firmware version that FW_VERSION reports
(1.x-3.06 old, 3.07-7.x current; others refused: :mod:`labkit.devices.motor.vesc_values`,
docs/reference/devices-tach-motor.md). Payloads over 512 bytes are refused, and set commands round like
VESC Tool (half away from zero); docs/explanation/hardware-fidelity.md lists the sources.
"""

from __future__ import annotations

import math
import struct
from typing import Any

from labkit.devices.base import MotorStatus
from labkit.devices.motor.keepalive import KeepAliveMotor
from labkit.devices.motor.vesc_values import CURRENT_HEAD, layout_for_firmware
from labkit.devices.motor.vesc_values import FAULT_CODES as FAULT_CODES  # re-exported
from labkit.devices.motor.vesc_values import VescValues as VescValues
from labkit.devices.motor.vesc_values import fault_name as fault_name
from labkit.devices.motor.vesc_values import parse_values as parse_values
from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.errors import DeviceError, DeviceTimeout
from labkit.units import RAD_S_PER_RPM

COMM_FW_VERSION = 0
COMM_GET_VALUES = 4
COMM_SET_DUTY = 5
COMM_SET_CURRENT = 6
COMM_SET_CURRENT_BRAKE = 7
COMM_SET_RPM = 8
COMM_REBOOT = 29
COMM_ALIVE = 30

#: PACKET_MAX_PL_LEN of comm/packet.h (firmware 4.00 on; 3.x allowed 1024): longer
#: payloads are refused, never framed
MAX_PAYLOAD = 512


def _crc16_bitwise(byte: int) -> int:
    crc = byte << 8
    for _ in range(8):
        crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


_CRC16_TABLE = tuple(_crc16_bitwise(i) for i in range(256))


def crc16_xmodem(data: bytes) -> int:
    """CRC-16/XMODEM: poly 0x1021, init 0, no reflection, no final xor (table-driven)."""
    crc = 0
    table = _CRC16_TABLE
    for byte in data:
        crc = ((crc << 8) & 0xFFFF) ^ table[(crc >> 8) ^ byte]
    return crc


def format_packet(payload: bytes) -> bytes:
    """Frame a payload: start byte, length, payload, CRC-16 (big-endian), 0x03."""
    if not 0 < len(payload) <= MAX_PAYLOAD:
        raise ValueError(f"payload length {len(payload)} not in 1..{MAX_PAYLOAD} (PACKET_MAX_PL_LEN)")
    head = bytes([2, len(payload)]) if len(payload) <= 255 else b"\x03" + struct.pack(">H", len(payload))
    return head + payload + struct.pack(">H", crc16_xmodem(payload)) + b"\x03"


def parse_packet(buffer: bytes | bytearray) -> tuple[bytes | None, int]:
    """Look at the start of ``buffer``: (payload, bytes consumed) for a whole valid packet,
    (None, 1) when the first byte cannot start one (drop it and rescan), (None, 0) when
    more bytes are needed."""
    if not buffer:
        return None, 0
    start = buffer[0]
    if start == 2:
        if len(buffer) < 2:
            return None, 0
        length, head = buffer[1], 2
        valid = length > 0
    elif start == 3:
        if len(buffer) < 3:
            return None, 0
        length, head = (buffer[1] << 8) | buffer[2], 3
        valid = length >= 255
    else:
        return None, 1
    if not valid or length > MAX_PAYLOAD:
        return None, 1
    total = head + length + 3
    if len(buffer) < total:
        return None, 0
    payload = bytes(buffer[head:head + length])
    crc = (buffer[head + length] << 8) | buffer[head + length + 1]
    if buffer[total - 1] != 3 or crc != crc16_xmodem(payload):
        return None, 1
    return payload, total


class VescFramer:
    """Byte stream -> payloads, resyncing one byte at a time like the firmware."""

    def __init__(self) -> None:
        self.buffer = bytearray()
        self.dropped = 0

    def feed(self, data: bytes) -> list[bytes]:
        self.buffer += data
        out: list[bytes] = []
        while self.buffer:
            payload, used = parse_packet(self.buffer)
            if used == 0:
                # Waiting for the rest of a packet. If a complete valid packet already
                # starts later, the first byte was a false start whose length field lies
                # (the firmware recovers from that with its receive timeout).
                later = self._later_packet_start()
                if later is None:
                    break
                del self.buffer[:later]
                self.dropped += later
                continue
            del self.buffer[:used]
            if payload is None:
                self.dropped += 1
            else:
                out.append(payload)
        return out

    def _later_packet_start(self) -> int | None:
        for i in range(1, len(self.buffer)):
            if self.buffer[i] in (2, 3) and parse_packet(self.buffer[i:])[0] is not None:
                return i
        return None


def round_half_away(value: float) -> int:
    """Round as VESC Tool does (vbytearray.cpp ``roundDouble``): halves away from zero."""
    return int(math.ceil(value - 0.5)) if value < 0.0 else int(math.floor(value + 0.5))


def _int32(value: float) -> bytes:
    return struct.pack(">i", max(-(2**31), min(2**31 - 1, round_half_away(value))))


def format_set_duty(duty: float) -> bytes:
    """SET_DUTY packet, duty -1..1 as int32 x 100 000."""
    return format_packet(bytes([COMM_SET_DUTY]) + _int32(max(-1.0, min(1.0, duty)) * 100_000))


def format_set_rpm(erpm: float) -> bytes:
    """SET_RPM packet: electrical RPM as int32."""
    return format_packet(bytes([COMM_SET_RPM]) + _int32(erpm))


def format_set_current(amps: float) -> bytes:
    return format_packet(bytes([COMM_SET_CURRENT]) + _int32(amps * 1000))


def format_set_current_brake(amps: float) -> bytes:
    return format_packet(bytes([COMM_SET_CURRENT_BRAKE]) + _int32(amps * 1000))


def format_request(command_id: int) -> bytes:
    """A bare request/keep-alive packet (FW_VERSION, GET_VALUES, ALIVE, REBOOT)."""
    return format_packet(bytes([command_id]))


def parse_fw_version(payload: bytes) -> dict[str, Any]:
    """FW_VERSION payload: major, minor, NUL-terminated hardware name (tail ignored)."""
    if len(payload) < 3 or payload[0] != COMM_FW_VERSION:
        raise ValueError("not a FW_VERSION payload")
    name, nul, _ = payload[3:].partition(b"\x00")
    return {"firmware": f"{payload[1]}.{payload[2]:02d}",
            "hardware": name.decode("ascii", "replace") if nul else ""}


def parse_firmware_option(text: str) -> tuple[int, int]:
    """``"3.00"`` / ``"6.2"`` -> (major, minor) as FW_VERSION reports them."""
    major, dot, minor = str(text).strip().partition(".")
    try:
        if not dot:
            raise ValueError
        return int(major), int(minor)
    except ValueError:
        raise ValueError(f"vesc option firmware={text!r}: expected MAJOR.MINOR, e.g. 3.00") from None


@register_driver
class Vesc(KeepAliveMotor):
    """VESC over UART or USB.

    Options: ``pole_pairs`` (motor pole pairs, default 1: ERPM = RPM x pole pairs),
    ``brake_current_a`` (stop() brakes with this current; 0 = release/coast; default 2 A),
    ``reply_timeout_s`` (0.2), ``firmware`` (``MAJOR.MINOR``: the GET_VALUES layout to
    decode; default: asked with FW_VERSION before the first GET_VALUES).
    """

    protocol = "vesc"
    option_names = frozenset({"brake_current_a", "firmware", "pole_pairs", "reply_timeout_s", "timeout_ms"})
    watchdog_option = "timeout_ms"
    watchdog_advice = ("set VESC Tool > App Settings > General > 'Timeout' to 500-1000 ms "
                       "(firmware default 1000 ms) and write the app configuration")
    default_serial = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}
    supports_speed_command = True

    def __init__(self, port: Any, clock: Any, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        self.pole_pairs = int(options.get("pole_pairs", 1))
        if self.pole_pairs < 1:
            raise ValueError(f"vesc option pole_pairs={self.pole_pairs}: must be >= 1")
        self.brake_current_a = float(options.get("brake_current_a", 2.0))
        self.reply_timeout_s = float(options.get("reply_timeout_s", 0.2))
        self.framer = VescFramer()
        self.last_reply = b""
        firmware = options.get("firmware")
        self.firmware: tuple[int, int] | None = (
            None if firmware in (None, "") else parse_firmware_option(str(firmware)))
        self.mode: tuple[str, float] | None = None  # ("duty", d) or ("erpm", e)
        self.flush_input("open")

    def request(self, command_id: int, label: str) -> bytes:
        """Send a request and return the reply payload with the same ID (others skipped)."""
        self.check_keepalive()
        with self.io_lock:
            self.flush_input(label)
            self.framer = VescFramer()
            self.write(format_request(command_id), label)
            deadline = self.clock.now() + self.reply_timeout_s
            while True:
                for payload in self.framer.feed(self.read_available(label)):
                    if payload[0] == command_id:
                        return payload
                if self.clock.now() >= deadline:
                    raise DeviceTimeout(self.name, label, self.last_bytes,
                                        f"no valid reply packet in {self.reply_timeout_s} s")
                self.clock.sleep(0.001)

    def values(self) -> VescValues:
        """GET_VALUES decoded in the layout of the controller's firmware (asked once)."""
        if self.firmware is None:
            self.identify()
        assert self.firmware is not None
        try:
            layout_for_firmware(*self.firmware)
        except ValueError as exc:
            raise DeviceError(self.name, "GET_VALUES", self.last_reply, str(exc)) from None
        payload = self.request(COMM_GET_VALUES, "GET_VALUES")
        self.last_reply = payload
        try:
            return parse_values(payload, self.firmware)
        except ValueError as exc:
            raise DeviceError(self.name, "GET_VALUES", payload, str(exc)) from None

    def identify(self) -> dict[str, Any]:
        payload = self.request(COMM_FW_VERSION, "FW_VERSION")
        self.last_reply = payload
        try:
            info = parse_fw_version(payload)
        except ValueError as exc:
            raise DeviceError(self.name, "FW_VERSION", payload, str(exc)) from None
        if self.firmware is None:
            self.firmware = (payload[1], payload[2])
        return {"model": "vesc", **info}

    def enable(self) -> None:
        """VESC has no safe start: start the 20 Hz keep-alive (ALIVE until a setpoint)."""
        self.check_keepalive()
        self.mode = None
        self.enabled = True
        self.send_setpoint()
        self.start_keepalive()

    def set_duty(self, duty: float) -> None:
        self.require_enabled("SET_DUTY")
        self.mode = ("duty", max(-1.0, min(1.0, self.finite(duty, "SET_DUTY"))))
        self.send_setpoint()

    def set_speed(self, speed_rad_s: float) -> None:
        """Closed-loop speed in the controller: SET_RPM with ERPM = RPM x pole pairs."""
        self.require_enabled("SET_RPM")
        self.mode = ("erpm", self.finite(speed_rad_s, "SET_RPM") / RAD_S_PER_RPM * self.pole_pairs)
        self.send_setpoint()

    def send_setpoint(self) -> None:
        if self.mode is None:
            self.write(format_request(COMM_ALIVE), "ALIVE")
        elif self.mode[0] == "duty":
            self.write(format_set_duty(self.mode[1]), f"SET_DUTY {self.mode[1]:.4f}")
        else:
            self.write(format_set_rpm(self.mode[1]), f"SET_RPM {self.mode[1]:.0f}")

    def send_zero(self) -> None:
        self.mode = None
        if self.brake_current_a > 0:
            self.write(format_set_current_brake(self.brake_current_a), "SET_CURRENT_BRAKE")
        else:
            self.write(format_set_current(0.0), "SET_CURRENT 0")

    def status(self) -> MotorStatus:
        v = self.values()
        errors = set() if v.fault_code == 0 else {v.fault}
        if v.timeout_active:
            errors.add("comm_timeout")
        target = self.mode[1] if self.mode and self.mode[0] == "duty" else 0.0
        return MotorStatus(
            t=self.clock.now(), duty=v.duty, target_duty=target,
            speed_rad_s=v.erpm / self.pole_pairs * RAD_S_PER_RPM,
            input_voltage_v=v.input_voltage_v, temperature_c=v.temp_mosfet_c,
            errors=frozenset(errors), raw=self.last_reply,
        )


SAMPLE_VALUES_PACKET = format_packet(
    bytes([COMM_GET_VALUES]) + CURRENT_HEAD.pack(250, 300, 150, 120, 0, 150, 500, 30000, 243,
                                                  0, 0, 0, 0, 1000, 1000, 0) + bytes(20))


def _parse_values_packet(data: bytes) -> VescValues:
    payload, _ = parse_packet(data)
    if payload is None:
        raise ValueError("bad packet")
    return parse_values(payload)


register_parser_benchmark("vesc", SAMPLE_VALUES_PACKET, _parse_values_packet)
