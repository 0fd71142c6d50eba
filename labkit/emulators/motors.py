"""Motor-controller emulators: Pololu SMC G2 and the labkit ESC bridge, and the base every
motor emulator shares (the VESC is in :mod:`labkit.emulators.vesc_emulator`).

Each turns the host's commands into duty on the shared plant
(``plant.set_duty(duty, t, name=<option motor, default "rotor">)``) and answers queries
from the plant's state. They parse and format bytes with their own code, independent of
the drivers (docs/reference/devices-tach-motor.md#protocols,
docs/explanation/device-rules.md#emulator-faults).

Fault knobs besides the common ones (garbage, split, drop_reply, delay, disconnect_at,
reconnect_after, wrong_baud):

* ``overload`` - SMC/bridge: over-temperature error (bit 7) stops the motor; VESC: the first
  motion command trips fault 4 (absolute over-current), latched.
* ``low_vin`` - SMC: low-VIN error (bit 5).
* ``fault_code`` - VESC: report this fault code and refuse to run.
* ``reset_at`` - clock time (s after open) of a controller reset: SMC/bridge re-arm safe
  start and report reset flags; VESC reboots from the watchdog (fault 10, motor released).
* ``stall_at`` - s after open from which the motor does not follow its command: the rotor is
  jammed and stops whatever the duty, while the controller reports no error (a real
  controller heats). Also on a signal: ``labkit emulate --fault-on-usr2 ROLE:stall``.
"""

from __future__ import annotations

import math
import struct

from labkit.emulators.base import Emulator, register_emulator

TWO_PI = 2.0 * math.pi


def _flag(options: dict[str, str], key: str, default: bool) -> bool:
    value = options.get(key)
    if value is None:
        return default
    return value.strip().lower() in ("1", "true", "yes", "on")


class MotorEmulator(Emulator):
    kind = "motor"

    def __post_init__(self) -> None:
        super().__post_init__()
        self.motor_name = self.options.get("motor", "rotor")
        self.latency_s = float(self.options.get("latency_s", 0.001))
        self._reset_done = False
        #: clock times of every valid motion/keep-alive command received (rate checks)
        self.setpoint_times: list[float] = []

    def drive(self, duty: float, t: float) -> None:
        self.plant.set_duty(duty, t, name=self.motor_name)

    def speed_rad_s(self, t: float) -> float:
        return self.plant.speed(t, self.motor_name)

    def next_output_time(self, t: float) -> float | None:
        return self.next_ready_time()  # no unsolicited output, only replies

    def check_events(self, t: float) -> None:
        stall = self.faults.get("stall_at")
        motor = self.plant.motor(self.motor_name)
        if stall is not None and motor.stalled_at is None and self._opened_at is not None:
            motor.stalled_at = self._opened_at + stall
        at = self.faults.get("reset_at")
        if at is not None and not self._reset_done and self.since_open(t) >= at:
            self._reset_done = True
            self.on_reset(self._opened_at + at if self._opened_at is not None else t)

    def on_reset(self, t: float) -> None:
        self.power_on(t)

    def produce(self, t: float) -> None:
        self.check_events(t)
        self.check_timeout(t)

    def before_bytes(self, t: float) -> None:
        """What happens up to the arrival of host bytes at ``t``. A pty host that found them
        waiting after a late wake sets ``arrived_since`` (when it last looked): the command
        timeout is judged at that earliest arrival, as the real UART would have received them."""
        since = self.arrived_since
        self.check_events(t)
        self.check_timeout(t if since is None else min(t, since))

    def check_timeout(self, t: float) -> None:
        """Controller-side command timeouts (subclasses)."""

    def watchdog_deadline(self) -> float | None:
        """When the command timeout will stop the motor if no command comes (None: never)."""
        return None

    def receive(self, data: bytes, t: float) -> None:
        super().receive(data, t)
        # hand the timeout to the plant, so it stops the motor on time even if this port
        # is not used again (the tachometer's port still sees the speed fall)
        self.plant.motor(self.motor_name).watchdog_at = self.watchdog_deadline()


# ------------------------------------------------------------------------------------------
# Pololu Simple Motor Controller G2
# ------------------------------------------------------------------------------------------

def _smc_crc7(data: bytes) -> int:
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            if crc & 1:
                crc ^= 0x91
            crc >>= 1
    return crc


SMC_DATA_LENGTH = {0x83: 0, 0x85: 2, 0x86: 2, 0x89: 1, 0x8A: 1, 0x91: 2, 0x92: 1, 0xA1: 1,
                   0xA2: 3, 0xC2: 0, 0xE0: 0}
BIT_SAFE_START, BIT_SERIAL, BIT_TIMEOUT, BIT_LOW_VIN, BIT_OVER_TEMP = 0, 2, 3, 5, 7
SERIAL_FORMAT, SERIAL_CRC = 1 << 4, 1 << 5


@register_emulator
class PololuSmcEmulator(MotorEmulator):
    """Pololu SMC G2 (USB command port: baud does not matter).

    Options: ``device_number`` (13), ``crc`` (0/1: commands carry a CRC-7 byte),
    ``crc_responses`` (0/1: replies carry one, user's guide section 6.5), ``command_timeout_ms`` (0 = off),
    ``motor`` (plant motor, ``rotor``), ``vin_mv`` (12000), ``temperature_c`` (25),
    ``product_id`` (0xA1), ``firmware`` (``1.04``), ``latency_s`` (0.001).
    """

    protocol = "pololu_smc"
    commands = frozenset(SMC_DATA_LENGTH)
    variables: frozenset[int] | None = None  # all
    pololu_form = True
    default_timeout_ms = 0

    def __post_init__(self) -> None:
        super().__post_init__()
        self.device_number = int(self.options.get("device_number", 13))
        self.crc = _flag(self.options, "crc", False) and self.pololu_form
        self.crc_responses = _flag(self.options, "crc_responses", False) and self.pololu_form
        self.command_timeout_ms = float(self.options.get("command_timeout_ms", self.default_timeout_ms))
        self.vin_mv = int(self.options.get("vin_mv", 12000))
        self.temperature_c = float(self.options.get("temperature_c", 25.0))
        self.product_id = int(self.options.get("product_id", "0xA1"), 0)
        major, _, minor = self.options.get("firmware", "1.04").partition(".")
        self.firmware_bcd = (int(minor or "0", 16), int(major, 16))
        self.reset_flags = 0x0C

    def power_on(self, t: float) -> None:
        super().power_on(t)
        self.packet = bytearray()
        self.safe_start = True            # motor may not run until 83
        self.latched = 1 << BIT_SAFE_START
        self.occurred = self.latched
        self.serial_errors = 0
        self.target = 0
        self.running_speed = 0
        self.last_command_t = t
        self.drive(0.0, t)

    def on_reset(self, t: float) -> None:
        self.reset_flags = 0x24  # watchdog
        self.power_on(t)

    # ---- errors -------------------------------------------------------------------------
    def error_status(self) -> int:
        status = self.latched
        if self.faults.get("overload"):
            status |= 1 << BIT_OVER_TEMP
        if self.faults.get("low_vin"):
            status |= 1 << BIT_LOW_VIN
        return status

    def raise_error(self, bit: int, t: float) -> None:
        self.latched |= 1 << bit
        self.occurred |= 1 << bit
        self.apply(t)

    def serial_error(self, bits: int, t: float) -> None:
        self.serial_errors |= bits
        self.raise_error(BIT_SERIAL, t)

    def apply(self, t: float) -> None:
        """Drive the plant from target and errors (any error stops the motor)."""
        self.running_speed = 0 if self.error_status() else self.target
        self.drive(self.running_speed / 3200.0, t)

    def watchdog_deadline(self) -> float | None:
        if self.command_timeout_ms <= 0 or self.latched & (1 << BIT_TIMEOUT):
            return None
        return self.last_command_t + self.command_timeout_ms / 1000.0

    def check_timeout(self, t: float) -> None:
        if self.command_timeout_ms <= 0 or self.latched & (1 << BIT_TIMEOUT):
            return
        due = self.last_command_t + self.command_timeout_ms / 1000.0
        if t >= due:
            self.raise_error(BIT_TIMEOUT, due)

    # ---- bytes --------------------------------------------------------------------------
    def handle(self, data: bytes, t: float) -> None:
        self.before_bytes(t)
        for byte in data:
            self._byte(byte, t)

    def _byte(self, byte: int, t: float) -> None:
        if byte >= 0x80:
            if self.packet and not (self.packet == b"\xAA"):
                self.serial_error(SERIAL_FORMAT, t)  # previous packet cut short
            self.packet = bytearray([byte])
        elif not self.packet:
            self.stray(byte, t)
            return
        else:
            self.packet.append(byte)
        self._maybe_complete(t)

    def stray(self, byte: int, t: float) -> None:
        """A data byte outside any packet: a format error."""
        self.serial_error(SERIAL_FORMAT, t)

    def _maybe_complete(self, t: float) -> None:
        p = self.packet
        if p[0] == 0xAA:
            if not self.pololu_form:
                self.packet = bytearray()
                self.serial_error(SERIAL_FORMAT, t)
                return
            if len(p) < 3:
                return
            cmd, head = p[2] | 0x80, 3
        else:
            cmd, head = p[0], 1
        if cmd not in self.commands:
            self.packet = bytearray()
            self.serial_error(SERIAL_FORMAT, t)
            return
        need = head + SMC_DATA_LENGTH[cmd] + (1 if self.crc else 0)
        if len(p) < need:
            return
        packet, self.packet = bytes(p[:need]), bytearray()
        if self.crc:
            if _smc_crc7(packet[:-1]) != packet[-1]:
                self.serial_error(SERIAL_CRC, t)
                return
            packet = packet[:-1]
        if head == 3 and packet[1] != self.device_number:
            return  # for another device on the bus
        self.last_command_t = t
        self.execute(cmd, packet[head:], t)

    def execute(self, cmd: int, data: bytes, t: float) -> None:
        if cmd == 0x83:
            self.safe_start = False
            self.latched &= ~((1 << BIT_SAFE_START) | (1 << BIT_SERIAL) | (1 << BIT_TIMEOUT))
            self.apply(t)
        elif cmd in (0x85, 0x86, 0x89, 0x8A):
            self.setpoint_times.append(t)
            speed = data[0] | data[1] << 5 if cmd in (0x85, 0x86) else data[0] * 3200 // 127
            speed = min(speed, 3200)
            self.target = -speed if cmd in (0x86, 0x8A) else speed
            if self.safe_start and self.target:
                self.raise_error(BIT_SAFE_START, t)
            self.apply(t)
        elif cmd == 0x92:
            self.target = 0
            self.apply(t)
        elif cmd == 0xE0:
            self.target = 0
            self.safe_start = True
            self.apply(t)
        elif cmd == 0xA1:
            self.answer(struct.pack("<H", self.variable(data[0], t) & 0xFFFF), t)
        elif cmd == 0xA2:
            self.answer(b"\x00", t)
        elif cmd == 0xC2:
            minor, major = self.firmware_bcd
            self.answer(struct.pack("<HBB", self.product_id, minor, major), t)

    def answer(self, data: bytes, t: float) -> None:
        """Reply bytes, with the CRC-7 byte appended when CRC for responses is on."""
        self.reply(data + (bytes([_smc_crc7(data)]) if self.crc_responses else b""), t, self.latency_s)

    def variable(self, vid: int, t: float) -> int:
        if self.variables is not None and vid not in self.variables:
            return 0
        if vid == 0:
            return self.error_status()
        if vid == 1:
            value, self.occurred = self.occurred | self.error_status(), 0
            return value
        if vid == 2:
            value, self.serial_errors = self.serial_errors, 0
            return value
        if vid == 3:
            return 1 if self.error_status() else 0
        if vid == 20:
            return self.target
        if vid == 21:
            return self.running_speed
        if vid == 22:
            return 0xFF if self.running_speed else 32
        if vid == 23:
            return self.vin_mv
        if vid in (24, 25):
            return 1200 if self.faults.get("overload") else round(self.temperature_c * 10)
        if vid == 44:
            return round(abs(self.running_speed) / 3200 * 2500)
        if vid == 127:
            return self.reset_flags
        if vid in (28, 29):
            ms = int(self.since_open(t) * 1000)
            return ms & 0xFFFF if vid == 28 else ms >> 16
        return 0


# ------------------------------------------------------------------------------------------
# labkit ESC bridge (Arduino -> servo PWM -> hobby ESC)
# ------------------------------------------------------------------------------------------

@register_emulator
class EscBridgeEmulator(PololuSmcEmulator):
    """The labkit ESC bridge sketch: an SMC compact subset driving a one-direction ESC.

    ``85`` speed 0..3200 -> pulse 1000..2000 us -> plant duty 0..1; ``86`` -> 1000 us;
    ``92``/``E0`` -> 1000 us; ``A1`` variables 0/20/21/23/127. 500 ms command timeout.
    The ESC arms ``arm_s`` (1.0) after power-on; before that it ignores throttle.
    Debug lines ``P <us>``, ``ARM``, ``STOP``, ``?`` answer ``OK ...``/``ERR ...``.
    """

    protocol = "esc_bridge"
    serial_settings = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}
    commands = frozenset({0x83, 0x85, 0x86, 0x92, 0xA1, 0xE0})
    variables = frozenset({0, 20, 21, 23, 127})
    pololu_form = False
    default_timeout_ms = 500

    def __post_init__(self) -> None:
        super().__post_init__()
        self.arm_s = float(self.options.get("arm_s", 1.0))
        self._debug_line = bytearray()

    def power_on(self, t: float) -> None:
        super().power_on(t)
        self.armed_at = t + self.arm_s
        self.pulse_us = 1000
        self._debug_line = bytearray()

    def apply(self, t: float) -> None:
        self.target = max(0, self.target)   # one direction: reverse is zero throttle
        speed = 0 if self.error_status() else self.target
        self.running_speed = speed
        self.pulse_us = 1000 + speed * 1000 // 3200
        duty = (self.pulse_us - 1000) / 1000.0 if t >= self.armed_at else 0.0
        self.drive(duty, t)

    def stray(self, byte: int, t: float) -> None:
        if byte == 0x0A:
            line, self._debug_line = bytes(self._debug_line).strip(), bytearray()
            self.debug_command(line.decode("ascii", "replace"), t)
        elif len(self._debug_line) < 32:
            self._debug_line.append(byte)

    def debug_command(self, line: str, t: float) -> None:
        if not line:
            return
        word, _, arg = line.partition(" ")
        if word == "?":
            self.reply(f"OK pulse={self.pulse_us} errors={self.error_status()}\n".encode(), t, self.latency_s)
        elif word == "ARM":
            self.execute(0x83, b"", t)
            self.reply(b"OK\n", t, self.latency_s)
        elif word == "STOP":
            self.execute(0xE0, b"", t)
            self.reply(b"OK\n", t, self.latency_s)
        elif word == "P" and arg.strip().isdigit() and 1000 <= int(arg) <= 2000:
            self.last_command_t = t
            self.execute(0x85, bytes([((int(arg) - 1000) * 32 // 10) & 0x1F,
                                      ((int(arg) - 1000) * 32 // 10) >> 5]), t)
            self.reply(b"OK\n", t, self.latency_s)
        else:
            self.reply(b"ERR bad command\n", t, self.latency_s)
