"""VESC driver and emulator against the vendor's own sources (not labkit's reading of them).

Sources, all from public repositories:

* vedderb/bldc tag ``3.00`` (FW_VERSION 3.0), ``commands.c`` case COMM_GET_VALUES: six
  ``NTC_TEMP(ADC_IND_TEMP_MOS1..6)`` and ``ADC_IND_TEMP_PCB`` (float16 x10), then motor and
  input current (float32 x100), duty (float16 x1e3), rpm (float32 x1), input voltage
  (float16 x10), Ah, Ah charged, Wh, Wh charged (float32 x1e4), tachometer, tachometer abs
  (int32), fault (uint8). Tag ``3.07`` ``commands.c`` is the first with the current layout.
* vedderb/bldc master (FW 7.01, commit b9d287b3) ``datatypes.h`` ``mc_fault_code`` and
  ``comm/packet.h`` ``#define PACKET_MAX_PL_LEN 512``.
* vedderb/vesc_tool master (VT 7.01, commit 426a4f8e) ``vbytearray.cpp``:
  ``vbAppendDouble32`` rounds with ``roundDouble(x) = x < 0 ? ceil(x - 0.5) : floor(x + 0.5)``;
  ``commands.cpp`` ``setDutyCycle`` scales by 1e5, ``setCurrent`` by 1e3.
"""

from __future__ import annotations

import json
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.cli import main
from labkit.devices.motor.vesc import (
    FAULT_CODES,
    format_packet,
    format_set_current,
    format_set_current_brake,
    format_set_duty,
    parse_packet,
    parse_values,
    round_half_away,
)
from labkit.emulators.plant import reset_plants
from labkit.emulators.rig_plant import RigPlant
from labkit.emulators.vesc_emulator import VescEmulator
from labkit.errors import DeviceError
from labkit.io.clock import RealClock
from labkit.io.pty_host import PtyHost

pytestmark = pytest.mark.timeout(30)


@pytest.fixture(autouse=True)
def _fresh_plants():
    reset_plants()
    yield
    reset_plants()


def bldc_300_values(duty: float, erpm: int, vin: float, fault: int = 0) -> bytes:
    """A GET_VALUES payload written field by field from bldc 3.00 commands.c."""
    out = bytes([4])
    for temp_c in (41.2, 40.9, 41.5, 40.1, 39.8, 40.0, 35.5):   # MOS1..MOS6, PCB
        out += struct.pack(">h", round(temp_c * 10))
    out += struct.pack(">i", 1234) + struct.pack(">i", 310)        # currents x100
    out += struct.pack(">h", round(duty * 1000)) + struct.pack(">i", erpm)
    out += struct.pack(">h", round(vin * 10))
    out += struct.pack(">iiii", 50, 0, 1200, 0) + struct.pack(">ii", 777, 888) + bytes([fault])
    return out


def test_firmware_3_00_layout_decodes_duty_speed_and_voltage():
    payload = bldc_300_values(0.25, 21000, 24.3)
    v = parse_values(payload, firmware=(3, 0))
    assert v.layout == "legacy"
    assert v.duty == pytest.approx(0.25, abs=1e-9)
    assert v.erpm == 21000 and v.input_voltage_v == pytest.approx(24.3, abs=1e-9)
    assert v.temp_mosfet_c == pytest.approx(41.5) and v.temp_pcb_c == pytest.approx(35.5)
    assert v.temp_motor_c is None and v.id_a is None
    assert (v.current_motor_a, v.tachometer, v.tachometer_abs) == (12.34, 777, 888)
    # 3.06 still sends this layout; 3.07 (tag 3.07 commands.c) the current one
    assert parse_values(payload, firmware=(3, 6)).duty == pytest.approx(0.25)


def test_current_layout_still_decodes_for_3_07_and_7_01():
    from labkit.devices.motor.vesc import SAMPLE_VALUES_PACKET
    payload, _ = parse_packet(SAMPLE_VALUES_PACKET)
    assert payload is not None
    for firmware in ((3, 7), (6, 2), (7, 1)):
        v = parse_values(payload, firmware=firmware)
        assert (v.duty, v.erpm, v.input_voltage_v) == (0.5, 30000, 24.3)


@pytest.mark.parametrize("firmware", [(0, 9), (8, 0), (42, 1)])
def test_unknown_firmware_version_is_refused_by_name(firmware):
    expected = rf"firmware {firmware[0]}\.{firmware[1]:02d}: GET_VALUES layout unknown"
    with pytest.raises(ValueError, match=expected):
        parse_values(bldc_300_values(0.25, 21000, 24.3), firmware=firmware)


def test_fault_codes_19_to_33_carry_the_datatypes_h_names():
    names = {19: "brk", 20: "resolver_lot", 21: "resolver_dos", 22: "resolver_los",
             23: "flash_corruption_app_cfg", 24: "flash_corruption_mc_cfg",
             25: "encoder_no_magnet", 26: "encoder_magnet_too_strong", 27: "phase_filter",
             28: "encoder_fault", 29: "lv_output_fault", 30: "encoder_slip", 31: "overspeed",
             32: "underspeed", 33: "abs_overspeed"}
    assert {code: FAULT_CODES[code] for code in names} == names
    assert parse_values(bldc_300_values(0.0, 0, 24.0, fault=31), firmware=(3, 0)).fault == "overspeed"


def test_payloads_over_packet_max_pl_len_are_refused():
    assert parse_packet(format_packet(bytes(512)))[0] == bytes(512)
    with pytest.raises(ValueError, match="PACKET_MAX_PL_LEN"):
        format_packet(bytes(513))
    # a frame announcing 513 bytes is not a packet, whatever its CRC
    payload = bytes(513)
    from labkit.devices.motor.vesc import crc16_xmodem
    frame = b"\x03" + struct.pack(">H", 513) + payload + struct.pack(">H", crc16_xmodem(payload)) + b"\x03"
    assert parse_packet(frame) == (None, 1)


@pytest.mark.parametrize("value, scaled", [(0.5, 1), (-0.5, -1), (2.5, 3), (-2.5, -3), (1.49, 1),
                                           (-1.51, -2), (0.0, 0)])
def test_rounding_is_half_away_from_zero_like_vesc_tool(value, scaled):
    assert round_half_away(value) == scaled


def test_current_and_duty_ties_round_like_vesc_tool():
    # 0.0005 A x 1e3 = 0.5 and 0.0025 A x 1e3 = 2.5 exactly in binary: VESC Tool sends 1 and 3
    assert format_set_current(0.0005)[3:7] == struct.pack(">i", 1)
    assert format_set_current_brake(-0.0025)[3:7] == struct.pack(">i", -3)
    assert format_set_current(0.0025)[3:7] == struct.pack(">i", 3)
    # duty 1.5e-5 x 1e5 = 1.5 -> 2 counts
    assert format_set_duty(1.5e-5)[3:7] == struct.pack(">i", 2)


def test_probe_against_a_vesc_announcing_firmware_3_00_prints_true_values(capsys):
    """``labkit probe`` over a real pty against the emulator set to firmware 3.00."""
    clock = RealClock()
    plant = RigPlant()
    emulator = VescEmulator(plant=plant, options={"firmware": "3.00", "vin_v": "24.3"})
    with PtyHost(emulator, clock=clock) as host:
        clock.sleep(0.05)  # the controller powers on with the motor released
        plant.set_duty(0.25, clock.now(), name="rotor")  # as if another client had set it
        clock.sleep(0.3)
        before = plant.speed(clock.now())
        code = main(["probe", "motor", "--protocol", "vesc", "--port", host.path,
                     "--samples", "2", "--json"])
        after = plant.speed(clock.now())
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert json.loads(captured.err.splitlines()[0])["firmware"] == "3.00"
    for line in captured.out.splitlines():
        status = json.loads(line)
        assert status["value"] == pytest.approx(0.25, abs=1e-3)
        assert status["input_voltage_v"] == pytest.approx(24.3, abs=1e-9)
        # ERPM is sent as a whole number: one count is 2*pi/60 rad/s
        assert before - 0.2 <= status["speed_rad_s"] <= after + 0.2
        assert 0 < status["speed_rad_s"] < 2500


def test_driver_names_an_unknown_firmware_instead_of_decoding(capsys):
    code = main(["probe", "motor", "--protocol", "vesc", "--port",
                 "sim://vesc?firmware=9.01", "--samples", "1"])
    err = capsys.readouterr().err
    assert code == 2
    assert "firmware 9.01: GET_VALUES layout unknown" in err and "GET_VALUES" in err


def test_firmware_option_overrides_the_announced_version():
    from labkit.devices.registry import driver_class
    from labkit.io.clock import VirtualClock
    from labkit.io.ports import open_port

    clock = VirtualClock()
    cls = driver_class("motor", "vesc")
    port = open_port("sim://vesc?firmware=3.00&vin_v=12.0", clock=clock, timeout=0, **cls.default_serial)
    with cls(port, clock, name="vesc", firmware="3.00") as motor:
        assert motor.status().input_voltage_v == pytest.approx(12.0)  # no FW_VERSION asked
    port = open_port("sim://vesc?firmware=3.00&vin_v=12.0", clock=clock, timeout=0, **cls.default_serial)
    with cls(port, clock, name="vesc", firmware="6.02") as motor, pytest.raises(DeviceError):
        motor.status()  # the old 56-byte reply is too short for the layout the user forced


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=120), st.tuples(st.integers(0, 12), st.integers(0, 120)))
def test_fuzz_values_decode_or_refuse_for_any_firmware(payload, firmware):
    """Any bytes under any announced version: a decoded reply or a ValueError, nothing else."""
    try:
        values = parse_values(bytes([4]) + payload, firmware=firmware)
    except ValueError:
        return
    assert values.layout in ("legacy", "current")


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(-32768, 32767), min_size=7, max_size=7),
       st.integers(-(2**31), 2**31 - 1), st.integers(-32768, 32767), st.integers(0, 255))
def test_fuzz_legacy_layout_round_trips_the_bldc_300_fields(temps, erpm, duty_counts, fault):
    payload = (bytes([4]) + struct.pack(">7h", *temps) + struct.pack(">ii", 5, -7)
               + struct.pack(">hih", duty_counts, erpm, 243) + struct.pack(">iiiiii", 1, 2, 3, 4, 9, 10)
               + bytes([fault]))
    v = parse_values(payload, firmware=(3, 0))
    assert v.temp_mosfet_c == max(temps[:6]) / 10 and v.temp_pcb_c == temps[6] / 10
    assert (v.erpm, v.duty, v.fault_code) == (erpm, duty_counts / 1000, fault)
    assert (v.current_motor_a, v.current_in_a, v.input_voltage_v) == (0.05, -0.07, 24.3)
    assert (v.tachometer, v.tachometer_abs) == (9, 10)
