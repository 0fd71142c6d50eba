"""Pololu Simple Motor Controller G2
(docs/reference/devices-tach-motor.md#pololu_smc-pololu-simple-motor-controller-g2): brushed DC, open-loop
duty cycle.

Binary commands, no terminator; every command byte has its MSB set and every data byte is
7-bit. Two packet forms:

* compact: ``cmd data...``
* Pololu (multi-drop): ``AA device cmd&7F data...`` (device number 0..127, default 13)

With the CRC option a CRC-7 byte (poly 0x91 reflected, init 0, LSB first) follows every
packet; ``crc7(b"\\x83") == 0x1A``. The controller's separate "CRC for responses" setting
(SMC G2 user's guide, section 6.5) appends a CRC-7 of the reply bytes to every reply:
option ``crc_responses``. The motor does not run after power-up, an error or
``E0`` until Exit Safe Start (``83``) is received. Speed is -3200..3200 (= -100..100 %
duty), sent as ``85``/``86`` (forward/reverse) with two 7-bit bytes (low 5 bits, high 7).
The controller never answers set commands; Get Variable (``A1 id``) answers two bytes
little-endian, Get Firmware Version (``C2``) four bytes.
"""

from __future__ import annotations

from typing import Any, ClassVar

from labkit.devices.base import MotorStatus
from labkit.devices.motor.keepalive import KeepAliveMotor, as_bool
from labkit.devices.registry import register_driver, register_parser_benchmark
from labkit.errors import DeviceError

MAX_SPEED = 3200

CMD_EXIT_SAFE_START = 0x83
CMD_FORWARD = 0x85
CMD_REVERSE = 0x86
CMD_SET_CURRENT_LIMIT = 0x91
CMD_BRAKE = 0x92
CMD_GET_VARIABLE = 0xA1
CMD_SET_MOTOR_LIMIT = 0xA2
CMD_GET_FIRMWARE_VERSION = 0xC2
CMD_STOP = 0xE0

VAR_ERROR_STATUS = 0
VAR_ERRORS_OCCURRED = 1
VAR_SERIAL_ERRORS = 2
VAR_LIMIT_STATUS = 3
VAR_TARGET_SPEED = 20
VAR_SPEED = 21
VAR_BRAKE_AMOUNT = 22
VAR_INPUT_VOLTAGE = 23
VAR_TEMPERATURE_A = 24
VAR_TEMPERATURE_B = 25
VAR_CURRENT_MA = 44
VAR_RESET_FLAGS = 127

SIGNED_VARIABLES = frozenset({VAR_TARGET_SPEED, VAR_SPEED})

#: error-status bits 0..9 (variables 0 and 1)
ERROR_BITS = (
    "safe_start_violation", "required_channel_invalid", "serial_error", "command_timeout",
    "limit_or_kill_switch", "low_vin", "high_vin", "over_temperature", "motor_driver_error",
    "err_line_high",
)
SERIAL_ERROR_BITS = {1: "frame", 2: "noise", 3: "rx_overrun", 4: "format", 5: "crc"}
RESET_FLAGS = {0x04: "reset_pin", 0x0C: "power_or_brownout", 0x14: "software", 0x24: "watchdog"}


def crc7(data: bytes) -> int:
    """Pololu CRC-7 of a packet (poly 0x91 reflected, init 0, LSB first)."""
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0x48 if crc & 1 else crc >> 1
    return crc


def format_command(cmd: int, data: bytes = b"", device_number: int | None = None,
                   crc: bool = False) -> bytes:
    """One packet: compact when ``device_number`` is None, else Pololu protocol; + CRC-7."""
    if not 0x80 <= cmd <= 0xFF:
        raise ValueError(f"command byte 0x{cmd:02X} must have its MSB set")
    if any(b > 0x7F for b in data):
        raise ValueError(f"data bytes must be 7-bit: {data.hex(' ')}")
    if device_number is None:
        packet = bytes([cmd]) + data
    else:
        if not 0 <= device_number <= 127:
            raise ValueError(f"device number {device_number} not in 0..127")
        packet = bytes([0xAA, device_number, cmd & 0x7F]) + data
    return packet + bytes([crc7(packet)]) if crc else packet


def speed_command(speed: int) -> tuple[int, bytes]:
    """Speed -3200..3200 -> (``85`` forward or ``86`` reverse, two 7-bit data bytes)."""
    if not -MAX_SPEED <= speed <= MAX_SPEED:
        raise ValueError(f"speed {speed} not in -3200..3200")
    magnitude = abs(speed)
    return (CMD_REVERSE if speed < 0 else CMD_FORWARD), bytes([magnitude & 0x1F, magnitude >> 5])


def duty_to_speed(duty: float) -> int:
    """Duty -1..1 -> SMC speed units (3200 = 100 %), clamped."""
    return round(max(-1.0, min(1.0, duty)) * MAX_SPEED)


def parse_variable(reply: bytes, variable_id: int) -> int:
    """Decode a 2-byte little-endian Get Variable reply (speeds are signed)."""
    if len(reply) != 2:
        raise ValueError(f"variable reply has {len(reply)} bytes, expected 2")
    return int.from_bytes(reply, "little", signed=variable_id in SIGNED_VARIABLES)


def decode_error_bits(value: int) -> frozenset[str]:
    """Error status/occurred bit field -> names (bits 0..9; higher bits are refused)."""
    if not 0 <= value < 1 << len(ERROR_BITS):
        raise ValueError(f"error status 0x{value:04X} has bits beyond bit 9")
    return frozenset(name for bit, name in enumerate(ERROR_BITS) if value >> bit & 1)


def parse_firmware_version(reply: bytes) -> dict[str, Any]:
    """``C2`` reply: product ID (uint16 LE), minor and major version in BCD [U: byte order]."""
    if len(reply) != 4:
        raise ValueError(f"firmware reply has {len(reply)} bytes, expected 4")
    minor, major = reply[2], reply[3]
    for bcd in (minor, major):
        if bcd >> 4 > 9 or bcd & 0xF > 9:
            raise ValueError(f"version byte 0x{bcd:02X} is not BCD")
    return {"product_id": int.from_bytes(reply[:2], "little"),
            "firmware": f"{major:X}.{minor:02X}"}  # BCD: hex digits are the decimal digits


def strip_response_crc(reply: bytes) -> bytes:
    """A reply with its CRC-7 byte (SMC G2 guide 6.5) -> the data; ValueError on a mismatch."""
    if len(reply) < 2:
        raise ValueError(f"reply of {len(reply)} bytes has no CRC byte")
    data, crc = reply[:-1], reply[-1]
    if crc != crc7(data):
        raise ValueError(f"response CRC 0x{crc:02X} does not match 0x{crc7(data):02X} of the data")
    return data


def _plausible(variable_id: int, value: int) -> bool:
    if variable_id in (VAR_ERROR_STATUS, VAR_ERRORS_OCCURRED):
        return value < 1 << len(ERROR_BITS)
    if variable_id in SIGNED_VARIABLES:
        return -MAX_SPEED <= value <= MAX_SPEED
    if variable_id in (VAR_TEMPERATURE_A, VAR_TEMPERATURE_B):
        return value <= 3000
    return True


@register_driver
class PololuSmc(KeepAliveMotor):
    """Pololu SMC G2 over its USB command port or TTL serial.

    Options: ``device_number`` (0..127: use the Pololu protocol; default: compact),
    ``crc`` (append CRC-7, must match the controller's setting), ``autobaud`` (send 0xAA on
    open so a TTL controller in auto-detect mode learns the rate; default on with the Pololu
    protocol), ``crc_responses`` (the controller appends a CRC-7 byte to its replies: its
    "CRC for responses" setting), ``reply_timeout_s`` (0.1), ``quiet_s`` (0.003: silence
    required after a reply).
    """

    protocol = "pololu_smc"
    option_names = frozenset({"autobaud", "command_timeout_ms", "crc", "crc_responses", "device_number",
                              "quiet_s", "reply_timeout_s"})
    watchdog_option = "command_timeout_ms"
    watchdog_advice = ("set 'Command timeout' to 500 ms in the Pololu Simple Motor Control Center G2 "
                       "(Input settings tab) and click Apply settings")
    default_serial = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}
    #: variables read by status()
    status_variables: ClassVar[tuple[int, ...]] = (
        VAR_ERROR_STATUS, VAR_TARGET_SPEED, VAR_SPEED, VAR_INPUT_VOLTAGE, VAR_TEMPERATURE_A)
    allow_reverse: ClassVar[bool] = True
    has_firmware_version: ClassVar[bool] = True

    def __init__(self, port: Any, clock: Any, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        number = options.get("device_number")
        self.device_number = None if number in (None, "") else int(number)
        self.crc = as_bool(options.get("crc", False))
        self.crc_responses = as_bool(options.get("crc_responses", False))
        self.reply_timeout_s = float(options.get("reply_timeout_s", 0.1))
        self.quiet_s = float(options.get("quiet_s", 0.003))
        self.target_speed = 0
        self.last_reply = b""
        self.flush_input("open")
        if as_bool(options.get("autobaud", self.device_number is not None)):
            self.write(b"\xAA", "autobaud 0xAA")

    # ---- packets ------------------------------------------------------------------------
    def packet(self, cmd: int, data: bytes = b"") -> bytes:
        return format_command(cmd, data, self.device_number, self.crc)

    def send(self, cmd: int, data: bytes = b"", label: str = "") -> None:
        self.write(self.packet(cmd, data), label or f"0x{cmd:02X}")

    def read_reply(self, n: int, label: str) -> bytes:
        """The ``n`` data bytes of a reply, its CRC byte checked and dropped when the
        controller sends one; a reply one byte too long says which option to set."""
        extra = 1 if self.crc_responses else 0
        try:
            reply = self.read_exact(n + extra, self.reply_timeout_s, label, self.quiet_s)
        except DeviceError as exc:
            if type(exc) is DeviceError and not extra and len(exc.last_bytes) == n + 1:
                raise DeviceError(self.name, label, exc.last_bytes,
                                  f"garbled reply: {n + 1} bytes where {n} were expected (a "
                                  "controller with CRC enabled for responses needs option "
                                  "crc_responses=1)") from None
            raise
        if not extra:
            return reply
        try:
            return strip_response_crc(reply)
        except ValueError as exc:
            raise DeviceError(self.name, label, reply, str(exc)) from None

    def get_variable(self, variable_id: int, attempts: int = 3) -> int:
        """Get Variable ``A1 id``; garbled replies are retried, then raise DeviceError."""
        self.check_keepalive()
        label = f"get variable {variable_id}"
        last: DeviceError | None = None
        for _ in range(attempts):
            with self.io_lock:
                self.flush_input(label)
                self.send(CMD_GET_VARIABLE, bytes([variable_id]), label)
                try:
                    reply = self.read_reply(2, label)
                except DeviceError as exc:
                    if type(exc) is not DeviceError:  # timeouts and disconnects go up at once
                        raise
                    last = exc
                    continue
            value = parse_variable(reply, variable_id)
            if _plausible(variable_id, value):
                self.last_reply = reply
                return value
            last = DeviceError(self.name, label, reply, f"implausible value {value}")
        assert last is not None
        raise last

    # ---- MotorController ----------------------------------------------------------------
    def identify(self) -> dict[str, Any]:
        if not self.has_firmware_version:
            return {"model": self.protocol}
        with self.io_lock:
            self.flush_input("get firmware version")
            self.send(CMD_GET_FIRMWARE_VERSION, label="get firmware version")
            reply = self.read_reply(4, "get firmware version")
        try:
            return {"model": "pololu-smc-g2", **parse_firmware_version(reply)}
        except ValueError as exc:
            raise DeviceError(self.name, "get firmware version", reply, str(exc)) from None

    def enable(self) -> None:
        """Exit safe start (``83``) and start the 20 Hz setpoint refresh at zero speed."""
        self.check_keepalive()
        self.target_speed = 0
        self.send(CMD_EXIT_SAFE_START, label="exit safe start")
        self.enabled = True
        self.start_keepalive()

    def set_duty(self, duty: float) -> None:
        self.require_enabled("set_duty")
        speed = duty_to_speed(self.finite(duty, "set_duty"))
        if speed < 0 and not self.allow_reverse:
            raise ValueError(f"{self.name}: duty {duty} < 0 but {self.protocol} drives one direction only")
        self.target_speed = speed
        self.send_setpoint()

    def send_setpoint(self) -> None:
        cmd, data = speed_command(self.target_speed)
        self.send(cmd, data, f"speed {self.target_speed}")

    def send_zero(self) -> None:
        self.target_speed = 0
        self.send(CMD_STOP, label="stop motor")

    def brake(self, amount: int = 32) -> None:
        """Brake (0 coast .. 32 full); ends the keep-alive, re-``enable()`` to run again."""
        if not 0 <= amount <= 32:
            raise ValueError(f"brake amount {amount} not in 0..32")
        self.enabled = False
        if self._job is not None:
            self._job.cancel()
            self._job = None
        self.target_speed = 0
        self.send(CMD_BRAKE, bytes([amount]), f"brake {amount}")

    def status(self) -> MotorStatus:
        values: dict[int, int] = {}
        raw = b""
        for vid in self.status_variables:
            values[vid] = self.get_variable(vid)
            raw += self.last_reply
        t = self.clock.now()
        temperature = values.get(VAR_TEMPERATURE_A)
        vin = values.get(VAR_INPUT_VOLTAGE)
        return MotorStatus(
            t=t,
            duty=values[VAR_SPEED] / MAX_SPEED,
            target_duty=values[VAR_TARGET_SPEED] / MAX_SPEED,
            input_voltage_v=None if vin is None else vin / 1000.0,
            temperature_c=None if temperature is None else temperature / 10.0,
            errors=decode_error_bits(values[VAR_ERROR_STATUS]),
            raw=raw,
        )

    def reset_flags(self) -> str:
        """Why the controller last reset (variable 127)."""
        value = self.get_variable(VAR_RESET_FLAGS)
        return RESET_FLAGS.get(value, f"0x{value:02X}")


register_parser_benchmark("pololu_smc", b"\x40\x06", lambda reply: parse_variable(reply, VAR_SPEED))
