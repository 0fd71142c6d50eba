"""Driver encoders against the independently written emulators (byte level, no ports):
whatever the driver formats, the emulated controller understands as meant."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.devices.motor.pololu_smc import (
    CMD_EXIT_SAFE_START,
    CMD_GET_VARIABLE,
    VAR_TARGET_SPEED,
    format_command,
    parse_variable,
    speed_command,
)
from labkit.devices.motor.vesc import (
    COMM_GET_VALUES,
    VescFramer,
    format_request,
    format_set_duty,
    format_set_rpm,
    parse_values,
)
from labkit.emulators.motors import PololuSmcEmulator
from labkit.emulators.rig_plant import RigPlant
from labkit.emulators.vesc_emulator import VescEmulator


def smc(crc: bool) -> PololuSmcEmulator:
    emulator = PololuSmcEmulator(plant=RigPlant(), options={"crc": "1" if crc else "0",
                                                            "device_number": "13"})
    emulator.open(0.0)
    return emulator


@settings(max_examples=150, deadline=None)
@given(st.integers(-3200, 3200), st.sampled_from([None, 13]), st.booleans())
def test_every_smc_speed_packet_sets_that_speed(speed, device, crc):
    emulator = smc(crc)
    emulator.receive(format_command(CMD_EXIT_SAFE_START, device_number=device, crc=crc), 0.0)
    emulator.receive(format_command(*speed_command(speed), device_number=device, crc=crc), 0.01)
    assert emulator.plant.motor("rotor").duty == pytest.approx(speed / 3200)
    emulator.receive(format_command(CMD_GET_VARIABLE, bytes([VAR_TARGET_SPEED]), device, crc), 0.02)
    assert parse_variable(emulator.emit(0.1), VAR_TARGET_SPEED) == speed


def test_smc_packet_for_another_device_number_is_ignored():
    emulator = smc(False)
    emulator.receive(format_command(CMD_EXIT_SAFE_START, device_number=5), 0.0)
    emulator.receive(format_command(*speed_command(1600), device_number=5), 0.01)
    assert emulator.plant.motor("rotor").duty == 0.0


def test_smc_packet_with_a_wrong_crc_is_ignored():
    emulator = smc(True)
    good = format_command(CMD_EXIT_SAFE_START, crc=True)
    emulator.receive(good[:-1] + bytes([good[-1] ^ 0x01]), 0.0)
    emulator.receive(format_command(*speed_command(1600), crc=True), 0.01)
    assert emulator.plant.motor("rotor").duty == 0.0          # still in safe start


@settings(max_examples=150, deadline=None)
@given(st.floats(-1.0, 1.0), st.integers(1, 14))
def test_vesc_duty_and_values_round_trip_through_the_emulator(duty, pole_pairs):
    plant = RigPlant()
    emulator = VescEmulator(plant=plant, options={"pole_pairs": str(pole_pairs)})
    emulator.open(0.0)
    emulator.receive(format_set_duty(duty), 0.0)
    assert plant.motor("rotor").duty == pytest.approx(duty, abs=1e-5)
    emulator.receive(format_request(COMM_GET_VALUES), 0.5)
    (payload,) = VescFramer().feed(emulator.emit(1.0))
    values = parse_values(payload)
    # first-order plant from rest: duty x max speed x (1 - exp(-t/tau)) at t = 0.5 s
    speed_rad_s = duty * 2500.0 * (1 - math.exp(-0.5 / 0.4))
    speed_rpm = speed_rad_s * 60 / (2 * math.pi)
    # duty travels as int32 x 1e5 and ERPM as an integer
    assert values.erpm == pytest.approx(speed_rpm * pole_pairs, abs=1.0 + 0.3 * pole_pairs)
    assert values.duty == pytest.approx(duty, abs=1e-3)


@settings(max_examples=100, deadline=None)
@given(st.integers(-90_000, 90_000))
def test_vesc_rpm_command_settles_at_that_erpm(erpm):
    plant = RigPlant()
    plant.motor("rotor").max_speed_rad_s = 20_000.0
    emulator = VescEmulator(plant=plant, options={"pole_pairs": "7"})
    emulator.open(0.0)
    emulator.receive(format_set_rpm(erpm), 0.0)
    emulator.receive(format_request(COMM_GET_VALUES), 0.9)     # within the 1 s timeout
    (payload,) = VescFramer().feed(emulator.emit(1.0))
    # 0.9 s = 2.25 time constants of the plant: 1 - exp(-2.25) of the way there
    assert parse_values(payload).erpm == pytest.approx(erpm * (1 - math.exp(-0.9 / 0.4)), abs=2.0)
