"""A rig with two rotors: each loop has its own tachometer; any interlock stops both motors."""

from pathlib import Path

import pytest

from labkit.control import build_speed_control
from labkit.emulators.plant import shared_plant
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import open_rig, parse_rig
from labkit.units import rpm_to_rad_s

BASE = (Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml").read_text()
SECOND = """
[devices.rotor2_motor]
kind = "motor"
protocol = "pololu_smc"
port = "sim://pololu_smc?seed=5&plant=model-fig525&role=rotor2_motor&motor=rotor2"
serial = { baudrate = 9600, timeout = 0.2 }

[devices.rotor2_tach]
kind = "tachometer"
protocol = "labkit_tach"
port = "sim://labkit_tach?seed=6&plant=model-fig525&role=rotor2_tach&rate_hz=20&source=rotor2{fault}"
serial = {{ baudrate = 115200, timeout = 0.2 }}
"""


def two_rotor_rig(fault=""):
    # the extra devices go before [bodies.rotator] so they stay inside [devices]
    extra = SECOND.replace("{fault}", fault).replace("{{", "{").replace("}}", "}")
    text = BASE.replace("[bodies.rotator]", extra + "\n[bodies.rotator]", 1)
    return parse_rig(text, "two-rotors.toml")


def test_both_loops_are_paired_by_role_and_reach_their_own_targets():
    rig = two_rotor_rig()
    assert {(lc.name, lc.motor, lc.tach) for lc in rig.control.loops} == {
        ("rotor", "rotor_motor", "rotor_tach"), ("rotor2", "rotor2_motor", "rotor2_tach")}
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(rig, clock)
        control = build_speed_control(opened, clock)
        control.set_targets({"rotor": rpm_to_rad_s(8000), "rotor2": rpm_to_rad_s(12000)})
        while not control.settled():
            clock.sleep(0.05)
            assert clock.now() < 30
        snaps = control.snapshots()
        control.stop()
        opened.close()
    assert snaps["rotor"].measured_rad_s == pytest.approx(rpm_to_rad_s(8000), rel=0.01)
    assert snaps["rotor2"].measured_rad_s == pytest.approx(rpm_to_rad_s(12000), rel=0.01)
    plant = shared_plant("model-fig525")
    assert plant.motor("rotor").duty == 0.0 and plant.motor("rotor2").duty == 0.0


def test_losing_one_tachometer_stops_both_motors_in_the_same_period():
    rig = two_rotor_rig("&faults=disconnect_at:5")
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(rig, clock)
        control = build_speed_control(opened, clock)
        control.set_targets({"rotor": rpm_to_rad_s(8000), "rotor2": rpm_to_rad_s(8000)})
        while control.tripped is None:
            clock.sleep(0.01)
            assert clock.now() < 30
        opened.close()
    assert "rotor2_tach" in control.tripped
    plant = shared_plant("model-fig525")
    t1 = plant.motor("rotor").zeroed_since(4.0)
    t2 = plant.motor("rotor2").zeroed_since(4.0)
    assert t1 is not None and t2 is not None
    assert t1 == t2  # the same tick stops both
    # disconnect_at counts from the emulator's open, which is after the other ports' (< 0.3 s)
    assert 5.0 < t1 <= 5.0 + 0.3 + 0.05 + 0.005
