"""VESC ``COMM_GET_VALUES`` replies: the two layouts firmware has sent, and fault names.

The layout depends on the firmware version the controller announces in ``COMM_FW_VERSION``
(docs/reference/devices-tach-motor.md, "VESC firmware versions"):

* ``legacy`` - firmware 1.x to 3.06: six MOSFET temperatures and a PCB temperature
  (int16 x10 each), motor and input current (int32 x100), duty (int16 x1000), ERPM
  (int32), input voltage (int16 x10), Ah, Ah charged, Wh, Wh charged (int32 x1e4),
  tachometer, absolute tachometer (int32), fault code (uint8): 55 bytes after the ID.
  No motor temperature, no d/q currents.
* ``current`` - firmware 3.07 on: MOSFET and motor temperature, motor, input, d and q
  current, then as above from duty; later versions append PID position, controller ID,
  three MOSFET temperatures, vd, vq and a status byte (parsed by length).

Unknown versions are refused: a layout guessed wrong turns 24.3 V into 2100 V.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

COMM_GET_VALUES = 4

#: mc_fault_code of datatypes.h (current firmware, 7.01)
FAULT_CODES = {
    0: "none", 1: "over_voltage", 2: "under_voltage", 3: "drv", 4: "abs_over_current",
    5: "over_temp_fet", 6: "over_temp_motor", 7: "gate_driver_over_voltage",
    8: "gate_driver_under_voltage", 9: "mcu_under_voltage", 10: "booting_from_watchdog_reset",
    11: "encoder_spi", 12: "encoder_sincos_below_min_amplitude",
    13: "encoder_sincos_above_max_amplitude", 14: "flash_corruption",
    15: "high_offset_current_sensor_1", 16: "high_offset_current_sensor_2",
    17: "high_offset_current_sensor_3", 18: "unbalanced_currents", 19: "brk",
    20: "resolver_lot", 21: "resolver_dos", 22: "resolver_los",
    23: "flash_corruption_app_cfg", 24: "flash_corruption_mc_cfg", 25: "encoder_no_magnet",
    26: "encoder_magnet_too_strong", 27: "phase_filter", 28: "encoder_fault",
    29: "lv_output_fault", 30: "encoder_slip", 31: "overspeed", 32: "underspeed",
    33: "abs_overspeed",
}

#: firmware versions whose layout has been checked against vedderb/bldc sources
LEGACY_UNTIL = (3, 6)        # 3.07 (tag 3.07, Nov 2016) introduced the current layout
KNOWN_MAJORS = range(1, 8)   # 1.x .. 7.x (7.01 is the newest checked)


class UnknownFirmware(ValueError):
    """A firmware version whose GET_VALUES layout labkit does not know."""


def fault_name(code: int) -> str:
    return FAULT_CODES.get(code, f"fault_{code}")


def layout_for_firmware(major: int, minor: int) -> str:
    """``"legacy"`` or ``"current"`` for firmware ``major.minor``; UnknownFirmware otherwise."""
    if major not in KNOWN_MAJORS or not 0 <= minor <= 99:
        raise UnknownFirmware(
            f"VESC firmware {major}.{minor:02d}: GET_VALUES layout unknown (labkit knows "
            f"1.00-3.06, old layout with six MOSFET temperatures, and 3.07-7.x)")
    return "legacy" if (major, minor) <= LEGACY_UNTIL else "current"


@dataclass(frozen=True)
class VescValues:
    """A decoded GET_VALUES reply. Fields a layout does not carry are None."""

    temp_mosfet_c: float
    temp_motor_c: float | None
    current_motor_a: float
    current_in_a: float
    id_a: float | None
    iq_a: float | None
    duty: float
    erpm: float
    input_voltage_v: float
    amp_hours: float
    amp_hours_charged: float
    watt_hours: float
    watt_hours_charged: float
    tachometer: int
    tachometer_abs: int
    fault_code: int
    pid_pos: float | None = None
    controller_id: int | None = None
    timeout_active: bool | None = None
    temp_pcb_c: float | None = None
    layout: str = "current"

    @property
    def fault(self) -> str:
        return fault_name(self.fault_code)


CURRENT_HEAD = struct.Struct(">hhiiiihihiiiiiiB")   # fields 0..15 (53 bytes)
LEGACY_HEAD = struct.Struct(">7hiihihiiiiiiB")      # 55 bytes


def _check(payload: bytes, size: int, layout: str) -> bytes:
    if not payload or payload[0] != COMM_GET_VALUES:
        raise ValueError("not a GET_VALUES payload")
    body = payload[1:]
    if len(body) < size:
        raise ValueError(f"GET_VALUES payload has {len(body)} bytes, the {layout} layout "
                         f"needs at least {size}")
    return body


def parse_current(payload: bytes) -> VescValues:
    """Firmware 3.07 on; tolerates the shorter replies of versions before the tail fields."""
    body = _check(payload, CURRENT_HEAD.size, "current")
    if len(body) == LEGACY_HEAD.size:  # no 3.07+ release sends 55 bytes (bldc tags 3.07-7.01)
        raise ValueError(f"GET_VALUES payload has {LEGACY_HEAD.size} bytes: the layout of "
                         "firmware 3.06 and older, not of the firmware version in use")
    (t_fet, t_mot, i_mot, i_in, i_d, i_q, duty, erpm, vin, ah, ahc, wh, whc,
     tach, tach_abs, fault) = CURRENT_HEAD.unpack_from(body)
    rest = body[CURRENT_HEAD.size:]
    pid_pos = struct.unpack_from(">i", rest)[0] / 1e6 if len(rest) >= 4 else None
    controller_id = rest[4] if len(rest) >= 5 else None
    timeout_active = bool(rest[19] & 1) if len(rest) >= 20 else None
    return VescValues(t_fet / 10, t_mot / 10, i_mot / 100, i_in / 100, i_d / 100, i_q / 100,
                      duty / 1000, float(erpm), vin / 10, ah / 1e4, ahc / 1e4, wh / 1e4, whc / 1e4,
                      tach, tach_abs, fault, pid_pos, controller_id, timeout_active)


def parse_legacy(payload: bytes) -> VescValues:
    """Firmware 1.x-3.06: the hottest of the six MOSFET sensors is ``temp_mosfet_c``."""
    body = _check(payload, LEGACY_HEAD.size, "legacy")
    fields = LEGACY_HEAD.unpack_from(body)
    mosfets, pcb = fields[:6], fields[6]
    (i_mot, i_in, duty, erpm, vin, ah, ahc, wh, whc, tach, tach_abs, fault) = fields[7:]
    return VescValues(max(mosfets) / 10, None, i_mot / 100, i_in / 100, None, None,
                      duty / 1000, float(erpm), vin / 10, ah / 1e4, ahc / 1e4, wh / 1e4,
                      whc / 1e4, tach, tach_abs, fault, temp_pcb_c=pcb / 10, layout="legacy")


def parse_values(payload: bytes, firmware: tuple[int, int] | None = None) -> VescValues:
    """Decode a GET_VALUES payload (ID 4) in the layout of ``firmware`` (major, minor).

    ``firmware=None`` assumes the current layout (3.07 on). UnknownFirmware (a ValueError)
    for a version whose layout is not known.
    """
    if firmware is not None and layout_for_firmware(*firmware) == "legacy":
        return parse_legacy(payload)
    return parse_current(payload)
