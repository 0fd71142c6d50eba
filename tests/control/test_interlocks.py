"""Interlocks on the emulated Fig. 5.25 rig (sim:// devices, virtual clock).

Each fault must end with every motor commanded to zero within one control period of the
moment the fault becomes observable, and a latched, explained interlock.
"""

from pathlib import Path

import pytest

from labkit.control import build_speed_control
from labkit.errors import SafetyError
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import open_rig, parse_rig
from labkit.units import rpm_to_rad_s

RIG = (Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml").read_text()
PERIOD = 0.05
READER = 0.005  # the tachometer reader's pump period


def start(rig_text, target_rpm, seconds=30.0):
    from labkit.emulators.plant import shared_plant

    rig = parse_rig(rig_text, "test.toml")
    clock = VirtualClock()
    events = []
    with use_clock(clock):
        opened = open_rig(rig, clock)
        control = build_speed_control(opened, clock, emit=events.append)
        control.started_at = clock.now()
        control.set_targets({"rotor": rpm_to_rad_s(target_rpm)})
        while control.tripped is None and clock.now() < seconds:
            clock.sleep(0.01)
    return control, opened, events, shared_plant("model-fig525"), clock


def test_speed_loop_reaches_and_holds_the_target():
    rig = parse_rig(RIG, "test.toml")
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(rig, clock)
        control = build_speed_control(opened, clock)
        control.set_targets({"rotor": rpm_to_rad_s(12000)})
        while not control.settled():
            clock.sleep(0.05)
            assert clock.now() < 20
        clock.sleep(2.0)
        speeds = [r.value for r in opened.devices["rotor_tach"].readings_since(clock.now() - 1.0)]
        control.stop()
        opened.close()
    assert min(speeds) == pytest.approx(rpm_to_rad_s(12000), rel=0.01)
    assert max(speeds) == pytest.approx(rpm_to_rad_s(12000), rel=0.01)


def test_ramp_rate_limit_is_respected():
    rig = parse_rig(RIG, "test.toml")
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(rig, clock)
        control = build_speed_control(opened, clock)
        control.set_targets({"rotor": rpm_to_rad_s(20000)})
        clock.sleep(1.0)
        snap = control.snapshots()["rotor"]
        control.stop()
        opened.close()
    # 6000 RPM/s from the rig file: after 1 s the setpoint is at most ~6000 RPM
    assert snap.setpoint_rad_s <= rpm_to_rad_s(6000) + 1e-6
    assert snap.setpoint_rad_s >= rpm_to_rad_s(5500)


def test_tachometer_unplugged_mid_run():
    text = RIG.replace("role=rotor_tach&", "role=rotor_tach&faults=disconnect_at:6&")
    control, opened, events, plant, clock = start(text, 10000)
    assert control.tripped and "tachometer rotor_tach lost" in control.tripped
    t_fault = 6.0 + 0.2 + 0.0  # disconnect_at counts from the emulator's open (t=0)
    zeroed = plant.motor("rotor").zeroed_since(t_fault - 0.5)
    assert zeroed is not None
    assert zeroed - 6.0 <= PERIOD + READER + 1e-9
    assert [e["type"] for e in events] == ["interlock"]
    with pytest.raises(SafetyError, match="interlock: tachometer"):
        control.check()
    opened.close()


def test_tachometer_silent_too_long():
    # a tachometer that reports only every 5 s: silence is a fault after tach_timeout (0.5 s)
    text = RIG.replace("rate_hz=20", "rate_hz=0.2")
    control, opened, events, plant, clock = start(text, 10000)
    assert "silent" in control.tripped
    t0 = control.started_at
    assert t0 + 0.5 <= control.tripped_at <= t0 + 0.5 + PERIOD + PERIOD
    assert plant.motor("rotor").duty == 0.0
    opened.close()


def test_implausible_tachometer_reading():
    # a Lutron display showing over-range ("OL") instead of a number
    text = RIG.replace('protocol = "labkit_tach"', 'protocol = "lutron16"').replace(
        "sim://labkit_tach?seed=2&plant=model-fig525&role=rotor_tach&rate_hz=20",
        "sim://lutron16?seed=2&plant=model-fig525&role=rotor_tach&rate_hz=20&faults=overload:1").replace(
        "baudrate = 115200", "baudrate = 9600")
    control, opened, events, plant, clock = start(text, 10000)
    assert "implausible reading nan" in control.tripped and "OL" in control.tripped
    first = opened.devices["rotor_tach"].readings_since(0.0)[0].t
    assert control.tripped_at - first <= PERIOD + 1e-9
    assert plant.motor("rotor").duty == 0.0
    opened.close()


def test_over_speed_from_a_wrong_feed_forward():
    # full_speed set to half the real one: feed-forward alone drives the rotor to twice the target
    text = RIG.replace("full_speed_rpm = 23873", "full_speed_rpm = 11000").replace(
        "max_speed_rpm = 24000", "max_speed_rpm = 12000")
    control, opened, events, plant, clock = start(text, 11500)
    assert control.tripped and control.tripped.startswith("over-speed")
    limit = rpm_to_rad_s(12000) * 1.05
    over = [r for r in opened.devices["rotor_tach"].readings_since(0.0) if r.value > limit]
    assert over, "the tachometer saw the over-speed"
    first = over[0].t
    assert first <= control.tripped_at <= first + PERIOD + 1e-9
    zeroed = plant.motor("rotor").zeroed_since(first)
    assert zeroed is not None and zeroed - first <= PERIOD + 1e-9
    opened.close()


def test_controller_error_flags_trip_at_the_first_status_read():
    text = RIG.replace("role=rotor_motor", "role=rotor_motor&faults=low_vin:1")
    control, opened, events, plant, clock = start(text, 10000)
    assert control.tripped and "reports errors" in control.tripped
    # the first tick (one period after the target was set) reads the status and trips
    assert control.tripped_at - control.started_at <= PERIOD + 0.05
    assert plant.motor("rotor").duty == 0.0
    clock.sleep(1.0)  # latched: nothing drives the motor again
    assert plant.motor("rotor").duty == 0.0
    opened.close()


def test_target_above_the_rig_limit_is_refused_before_anything_moves():
    rig = parse_rig(RIG, "test.toml")
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(rig, clock)
        control = build_speed_control(opened, clock)
        with pytest.raises(SafetyError, match="above the rig's limit of 24000 RPM"):
            control.set_targets({"rotor": rpm_to_rad_s(25000)})
        clock.sleep(0.5)
        opened.close()
    from labkit.emulators.plant import shared_plant

    assert shared_plant("model-fig525").motor("rotor").duty_changes == []
