"""Rig files: shipped rigs load, units become SI, every mistake is one `file:key: reason` line."""

import math
from pathlib import Path

import pytest

from labkit.errors import RigFileError
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import bundled_rig_names, bundled_rig_path, load_rig, open_rig, parse_rig

REPO = Path(__file__).resolve().parents[2]
RIGS = sorted((REPO / "rigs").glob("*.toml"))

MINIMAL = """
[rig]
name = "t"
[devices.rotor_motor]
kind = "motor"
protocol = "pololu_smc"
port = "sim://pololu_smc?plant=t"
[devices.rotor_tach]
kind = "tachometer"
protocol = "labkit_tach"
port = "sim://labkit_tach?plant=t"
[limits]
max_speed_rpm = 12000
max_ramp_rpm_per_s = 3000
"""


@pytest.mark.parametrize("path", RIGS, ids=[p.name for p in RIGS])
def test_every_shipped_rig_loads(path):
    rig = load_rig(path)
    assert rig.devices and rig.limits.max_speed_rad_s > 0
    assert rig.control.loops, "every shipped rig pairs a motor with a tachometer"


def test_bundled_rigs_are_identical_to_the_user_facing_copies():
    names = bundled_rig_names()
    assert {"emulated-fig525", "emulated-fig618"} <= set(names)
    for name in names:
        assert bundled_rig_path(name).read_bytes() == (REPO / "rigs" / f"{name}.toml").read_bytes()


def test_a_bundled_rig_loads_by_name():
    assert load_rig("emulated-fig525").name == "emulated-fig525"


def test_units_in_key_names_become_si():
    rig = parse_rig(MINIMAL + """
[bodies.floator]
shape = "sphere"
diameter_mm = 15
mass_g = 13.36
tilt_deg = 5
inertia_axial_g_mm2 = 300
[control]
settle_tolerance_rpm = 60
settle_hold_s = 2
""", "t.toml")
    assert rig.limits.max_speed_rad_s == pytest.approx(12000 * 2 * math.pi / 60)
    assert rig.limits.max_ramp_rad_s2 == pytest.approx(3000 * 2 * math.pi / 60)
    f = rig.bodies["floator"]
    assert f.diameter_m == pytest.approx(0.015)
    assert f.mass_kg == pytest.approx(0.01336)
    assert f.tilt_rad == pytest.approx(math.radians(5))
    assert f.inertia_axial_kg_m2 == pytest.approx(3e-7)
    assert rig.control.settle_tolerance_rad_s == pytest.approx(2 * math.pi)
    assert rig.control.loops[0].motor == "rotor_motor" and rig.control.loops[0].tach == "rotor_tach"


@pytest.mark.parametrize("change, key, reason", [
    (("[limits]", "[limits]\nmax_speed_bananas = 3"), "limits.max_speed_bananas", "unknown key"),
    (("max_speed_rpm = 12000", "max_speed_rpm = '12000'"), "limits.max_speed_rpm", "must be a number"),
    (("max_speed_rpm = 12000", "max_speed_rpm = -5"), "limits.max_speed_rpm", "must be > 0"),
    (("max_speed_rpm = 12000", "max_speed_mm = 5"), "limits.max_speed_mm", "wrong unit"),
    (("max_speed_rpm = 12000", "max_speed = 5"), "limits.max_speed", "needs a unit suffix"),
    (("max_speed_rpm = 12000\n", ""), "limits.max_speed_rpm", "missing (required)"),
    (('protocol = "pololu_smc"', 'protocol = "smc9000"'), "devices.rotor_motor.protocol", "no motor driver"),
    (('kind = "motor"', 'kind = "engine"'), "devices.rotor_motor.kind", "must be one of"),
    (('port = "sim://pololu_smc?plant=t"', "port = 7"), "devices.rotor_motor.port", "must be str"),
    (('port = "sim://pololu_smc?plant=t"', 'port = "ttyUSB0"'), "devices.rotor_motor.port", "neither"),
    (('name = "t"', 'name = "t"\nauthor = "me"'), "rig.author", "unknown key"),
    (("sim://labkit_tach?plant=t", "sim://labkit_tac?plant=t"), "devices.rotor_tach.port",
     "no emulator 'labkit_tac'"),
    (("sim://labkit_tach?plant=t", "sim://labkit_tach?plant=t&faults=garbge:0.1"),
     "devices.rotor_tach.port", "unknown fault 'garbge'"),
    (("sim://labkit_tach?plant=t", "sim://labkit_tach?plant=t&seed=one"), "devices.rotor_tach.port",
     "seed='one' is not an integer"),
    # a mistyped driver option would be ignored: a 2-pulse wheel read as 1 pulse doubles the speed
    (('port = "sim://labkit_tach?plant=t"',
      'port = "sim://labkit_tach?plant=t"\noptions = { pulses_per_rev = 2 }'),
     "devices.rotor_tach.options.pulses_per_rev", "unknown option 'pulses_per_rev' for labkit_tach; known: "),
])
def test_bad_rig_files_name_file_key_and_reason(change, key, reason):
    old, new = change
    assert old in MINIMAL
    with pytest.raises(RigFileError) as info:
        parse_rig(MINIMAL.replace(old, new, 1), "my-rig.toml")
    message = str(info.value)
    assert message.startswith(f"my-rig.toml:{key}: "), message
    assert reason in message
    assert "\n" not in message


@pytest.mark.parametrize("extra, key, reason", [
    ('[bodies.floator]\nshape = "sphere"\nmass_g = -13', "bodies.floator.mass_g", "must be > 0"),
    ('[bodies.floator]\nshape = "egg"', "bodies.floator.shape", "must be one of"),
    ('[bodies.moon]\nshape = "sphere"', "bodies.moon", "unknown body"),
    ('[devices.rotor_motor.serial]\nparity = "X"', "devices.rotor_motor.serial.parity", "must be N, E, O"),
    ('[devices.rotor_motor.serial]\nbaud = 9600', "devices.rotor_motor.serial.baud", "unknown key"),
    ('[control]\nkp = -1', "control.kp", "must be >= 0"),
    ('[[control.loops]]\nmotor = "rotor_motor"\ntach = "floator_tach"', "control.loops[0].tach",
     "not a tachometer device"),
])
def test_bad_sections(extra, key, reason):
    with pytest.raises(RigFileError) as info:
        parse_rig(MINIMAL + extra, "r.toml")
    assert str(info.value).startswith(f"r.toml:{key}: "), str(info.value)
    assert reason in str(info.value)


def test_toml_syntax_error_and_missing_file():
    with pytest.raises(RigFileError, match=r"^bad.toml:\(syntax\): "):
        parse_rig("[rig\nname=", "bad.toml")
    with pytest.raises(RigFileError, match=r"no such rig file"):
        load_rig("/nonexistent/rig.toml")


def test_open_rig_instantiates_drivers_and_close_zeroes_the_motor():
    from labkit.emulators.plant import reset_plants, shared_plant

    reset_plants()
    rig = load_rig(REPO / "rigs" / "emulated-fig525.toml")
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(rig, clock)
        assert set(opened.devices) == {"rotor_motor", "rotor_tach", "balance"}
        motor = opened.devices["rotor_motor"].raw_driver  # bare driver: no limits (bring-up)
        motor.enable()
        motor.set_duty(0.3)
        clock.sleep(0.5)
        plant = shared_plant("model-fig525")
        assert plant.motor("rotor").duty == pytest.approx(0.3, abs=0.01)
        opened.close()
        assert plant.motor("rotor").duty == 0.0
