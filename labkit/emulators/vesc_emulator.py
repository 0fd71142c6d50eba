"""The VESC emulator (``sim://vesc``): UART packets, GET_VALUES in the layout of the
firmware version it announces, SET_* commands driving the shared plant, the 1 s
communication timeout (docs/reference/devices-tach-motor.md#vesc-vesc-uart-packets; fault knobs in
:mod:`labkit.emulators.motors`).
"""

from __future__ import annotations

import struct

from labkit.emulators.base import register_emulator
from labkit.emulators.motors import TWO_PI, MotorEmulator


def _vesc_crc(data: bytes) -> int:
    crc = 0
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = (crc << 1) ^ 0x1021 if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def _vesc_frame(payload: bytes) -> bytes:
    return bytes([2, len(payload)]) + payload + struct.pack(">H", _vesc_crc(payload)) + b"\x03"


@register_emulator
class VescEmulator(MotorEmulator):
    """A VESC on its UART (115200 8N1).

    Options: ``pole_pairs`` (1), ``max_erpm`` (100000), ``timeout_ms`` (1000: release the
    motor when no set/alive packet arrives), ``vin_v`` (24.0), ``firmware`` (``6.02``),
    ``hardware`` (``labkit-emu``), ``reboot_s`` (0.5), ``motor`` (``rotor``).
    Firmware before 3.07 answers GET_VALUES in the old layout (six MOSFET temperatures and
    a PCB temperature; vedderb/bldc tag 3.00 ``commands.c``).
    """

    protocol = "vesc"
    serial_settings = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __post_init__(self) -> None:
        super().__post_init__()
        self.pole_pairs = int(self.options.get("pole_pairs", 1))
        self.max_erpm = float(self.options.get("max_erpm", 100_000))
        self.timeout_ms = float(self.options.get("timeout_ms", 1000))
        self.vin_v = float(self.options.get("vin_v", 24.0))
        major, _, minor = self.options.get("firmware", "6.02").partition(".")
        self.fw = (int(major), int(minor or 0))
        self.hardware = self.options.get("hardware", "labkit-emu")
        self.reboot_s = float(self.options.get("reboot_s", 0.5))
        self.fault = int(self.faults.get("fault_code", 0))

    def power_on(self, t: float) -> None:
        super().power_on(t)
        self.rx = bytearray()
        self.mode: tuple[str, float] | None = None
        self.last_command_t = t
        self.timed_out = False
        self.silent_until = t
        self.drive(0.0, t)

    def on_reset(self, t: float) -> None:
        self.power_on(t)
        self.silent_until = t + self.reboot_s
        self.fault = 10  # booting from watchdog reset

    def watchdog_deadline(self) -> float | None:
        if self.mode is None or self.timed_out or self.timeout_ms <= 0:
            return None
        return self.last_command_t + self.timeout_ms / 1000.0

    def check_timeout(self, t: float) -> None:
        if self.mode is None or self.timed_out or self.timeout_ms <= 0:
            return
        due = self.last_command_t + self.timeout_ms / 1000.0
        if t >= due:
            self.timed_out = True
            self.mode = None
            self.drive(0.0, due)

    def handle(self, data: bytes, t: float) -> None:
        self.before_bytes(t)
        if t < self.silent_until:
            return
        self.rx += data
        while self.rx:
            start = self.rx[0]
            if start != 2 or len(self.rx) >= 2 and self.rx[1] == 0:
                del self.rx[:1]
                continue
            if len(self.rx) < 2 or len(self.rx) < self.rx[1] + 5:
                return
            n = self.rx[1]
            payload = bytes(self.rx[2:2 + n])
            crc = struct.unpack(">H", self.rx[2 + n:4 + n])[0]
            if self.rx[4 + n] != 3 or crc != _vesc_crc(payload):
                del self.rx[:1]  # the firmware drops one byte and rescans; no NAK
                continue
            del self.rx[:n + 5]
            self.execute(payload, t)

    def _run(self, duty: float, t: float) -> None:
        if self.fault or (self.faults.get("overload") and duty):
            if self.faults.get("overload") and not self.fault:
                self.fault = 4
            self.mode = None
            self.drive(0.0, t)
            return
        self.drive(duty, t)

    def execute(self, payload: bytes, t: float) -> None:
        cid, body = payload[0], payload[1:]
        if cid in (5, 6, 7, 8, 30):
            self.setpoint_times.append(t)
            self.last_command_t = t
            self.timed_out = False
        if cid == 0:
            reply = (bytes([0, *self.fw]) + self.hardware.encode() + b"\x00" + bytes(12)
                     + b"\x00\x00\x00")
            self.reply(_vesc_frame(reply), t, self.latency_s)
        elif cid == 4:
            self.reply(_vesc_frame(self.values_payload(t)), t, self.latency_s)
        elif cid == 5 and len(body) == 4:
            duty = max(-1.0, min(1.0, struct.unpack(">i", body)[0] / 100_000))
            self.mode = ("duty", duty)
            self._run(duty, t)
        elif cid == 8 and len(body) == 4:
            erpm = max(-self.max_erpm, min(self.max_erpm, float(struct.unpack(">i", body)[0])))
            self.mode = ("erpm", erpm)
            max_speed = self.plant.motor(self.motor_name).max_speed_rad_s
            target = erpm / self.pole_pairs * TWO_PI / 60.0
            self._run(max(-1.0, min(1.0, target / max_speed)), t)
        elif cid == 6 and len(body) == 4:
            amps = struct.unpack(">i", body)[0] / 1000
            self.mode = ("current", amps) if amps else None
            self._run(max(-1.0, min(1.0, amps / 20.0)), t)
        elif cid == 7 and len(body) == 4:
            self.mode = ("brake", struct.unpack(">i", body)[0] / 1000)
            self.drive(0.0, t)
        elif cid == 29:
            self.on_reset(t)
            self.fault = 0

    def values_payload(self, t: float) -> bytes:
        speed = self.speed_rad_s(t)
        duty = self.plant.motor(self.motor_name).duty
        erpm = speed * 60.0 / TWO_PI * self.pole_pairs
        i_motor = 0.5 + 4.0 * abs(duty) if duty else 0.0
        t_fet = round(25.0 * 10 + abs(duty) * 100)
        i_mot, i_in = round(i_motor * 100), round(i_motor * abs(duty) * 100)
        from_duty = (round(duty * 1000), round(erpm), round(self.vin_v * 10), 0, 0, 0, 0,
                     0, 0, self.fault)
        if self.fw < (3, 7):  # bldc 3.00 commands.c: MOS1..MOS6, PCB, then no id/iq
            temps = (t_fet, t_fet - 3, t_fet - 1, t_fet - 2, t_fet - 4, t_fet - 5, 280)
            return bytes([4]) + struct.pack(">7hiihihiiiiiiB", *temps, i_mot, i_in, *from_duty)
        head = struct.pack(">hhiiiihihiiiiiiB", t_fet, round(30.0 * 10), i_mot, i_in, 0, i_mot,
                           *from_duty)
        tail = struct.pack(">iB", 0, 0) + struct.pack(">hhh", 250, 250, 250) + struct.pack(">ii", 0, 0)
        status = 1 if self.timed_out else 0
        return bytes([4]) + head + tail + bytes([status])
