"""Limits in every interface (issue 17, item 5): `open_rig` hands out rig-aware motor handles.

The issue's case: `open_rig(...).devices["rotor_motor"].set_duty(1.0)` on emulated-fig618
(limit 16 000 RPM, 6 000 RPM/s) reached 23 875 RPM with no ramp.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.emulators.plant import reset_plants, shared_plant
from labkit.errors import SafetyError
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import load_rig, open_rig, parse_rig
from labkit.units import rad_s_to_rpm

RIG = Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig618.toml"


@pytest.fixture
def rig_open():
    reset_plants()
    clock = VirtualClock()
    with use_clock(clock), open_rig(load_rig(RIG), clock) as opened:
        yield opened, clock, shared_plant("model-fig618").motor("rotor")
    reset_plants()


def rpm(motor) -> float:
    return rad_s_to_rpm(motor.speed_rad_s)


def test_set_duty_on_the_rig_handle_is_refused_and_nothing_moves(rig_open):
    opened, clock, motor = rig_open
    with pytest.raises(SafetyError, match="set_speed.*raw_driver"):
        opened.devices["rotor_motor"].set_duty(1.0)
    clock.sleep(2.0)
    motor.advance(clock.now())
    assert motor.duty == 0.0 and rpm(motor) < 1.0


def test_speed_above_the_rigs_limit_is_refused(rig_open):
    opened, clock, motor = rig_open
    with pytest.raises(SafetyError, match="above the rig's limit of 16000 RPM"):
        opened.devices["rotor_motor"].set_speed_rpm(20000)
    assert motor.duty == 0.0


def test_speeds_are_ramped_held_and_stopped_within_the_rig(rig_open):
    opened, clock, motor = rig_open
    handle = opened.devices["rotor_motor"]
    handle.set_speed_rpm(12000)
    handle.hold(1.0)
    snapshot = handle.control.snapshots()["rotor"]
    assert rad_s_to_rpm(snapshot.setpoint_rad_s) <= 6000 + 1e-6   # 6000 RPM/s from the rig file
    handle.wait_settled()
    handle.hold(1.0)
    assert handle.speed_rpm == pytest.approx(12000, rel=0.02)
    assert rpm(motor) == pytest.approx(12000, rel=0.02)
    handle.stop()
    assert motor.duty == 0.0


def test_an_exception_in_a_with_block_stops_the_motor(rig_open):
    opened, clock, motor = rig_open
    with pytest.raises(ZeroDivisionError), opened.devices["rotor_motor"] as handle:
        handle.set_speed_rpm(8000)
        handle.hold(1.5)
        assert motor.duty > 0
        _ = 1 / 0
    assert motor.duty == 0.0


def test_tachometer_loss_trips_the_handles_interlock():
    reset_plants()
    text = RIG.read_text().replace("role=rotor_tach&", "role=rotor_tach&faults=disconnect_at:1.5&")
    clock = VirtualClock()
    with use_clock(clock), open_rig(parse_rig(text, "rig.toml"), clock) as opened:
        handle = opened.devices["rotor_motor"]
        handle.set_speed_rpm(8000)
        with pytest.raises(SafetyError, match="rotor_tach"):
            handle.hold(5.0)
        assert shared_plant("model-fig618").motor("rotor").duty == 0.0
    reset_plants()


def test_the_raw_driver_is_there_explicitly(rig_open):
    opened, clock, motor = rig_open
    raw = opened.devices["rotor_motor"].raw_driver
    assert raw is opened.drivers["rotor_motor"] and raw.protocol == "pololu_smc"
    assert opened.devices["balance"] is opened.drivers["balance"]   # only motors are wrapped
