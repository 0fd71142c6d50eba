"""The labkit_strobe driver against its emulator (sim://labkit_strobe): it follows the plant's
rotor, obeys the commands and reports what it cannot do; on a virtual clock, in a rig with a
``strobe`` role, through ``labkit probe strobe``, and with the emulator in its own process
(``labkit emulate``) over real pseudo-terminals."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

import labkit.emulators  # noqa: F401 - registers sim://
from labkit.cli import main
from labkit.devices.registry import driver_class
from labkit.emulators.plant import shared_plant, use_emulation
from labkit.errors import DeviceReplyError, DeviceTimeout
from labkit.io.clock import RealClock, VirtualClock, use_clock
from labkit.io.ports import open_port
from labkit.rig import load_rig, open_rig

REPO = Path(__file__).resolve().parents[2]
TWO_PI = 2 * math.pi


def spin(plant: str, hz: float) -> None:
    motor = shared_plant(plant).motor("rotor")
    motor.max_speed_rad_s = max(motor.max_speed_rad_s, TWO_PI * 5000)
    motor.speed_rad_s = TWO_PI * hz
    motor.duty = motor.speed_rad_s / motor.max_speed_rad_s


def open_strobe(clock, query: str = "", **options):
    cls = driver_class("strobe", "labkit_strobe")
    port = open_port(f"sim://labkit_strobe?plant=strobe-test&seed=2{query}", clock=clock, timeout=0,
                     **cls.default_serial)
    return cls(port, clock, name="strobe", **options)


@pytest.fixture
def clock():
    with use_emulation():
        yield VirtualClock()


def test_follows_the_rotor_and_shows_the_offset(clock):
    spin("strobe-test", 420.0)
    with open_strobe(clock, rate_hz=10, offset_hz=0.75) as strobe:
        assert strobe.identify()["model"] == "labkit-strobe"
        clock.sleep(1.0)
        status = strobe.wait_status()
        assert status.rotor_hz == pytest.approx(420.0, rel=1e-4) and status.locked
        assert status.strobe_hz == pytest.approx(420.0 - 0.75, rel=1e-6)
        assert status.apparent_hz == pytest.approx(0.75, abs=2e-4)
        spin("strobe-test", 630.0)                         # the rotor speeds up: the lock follows
        strobe.set_divider(3)
        clock.sleep(0.5)
        status = strobe.wait_status()
        assert status.rotor_hz == pytest.approx(630.0, rel=1e-4) and status.divider == 3
        assert status.apparent_hz == pytest.approx(0.75, abs=2e-4)
        phases = [s.phase_deg for s in strobe.statuses_since(clock.now() - 0.35)]
        steps = [(b - a) % 360 for a, b in zip(phases, phases[1:], strict=False)]
        assert steps == pytest.approx([0.75 * 360 * 0.1] * len(steps), abs=0.2)  # D * 360 deg per 0.1 s


def test_what_it_cannot_do_is_flagged(clock):
    spin("strobe-test", 0.0)
    with open_strobe(clock, rate_hz=10) as strobe:
        clock.sleep(0.3)
        stopped = strobe.wait_status()
        assert {"no_pulses", "unlocked"} <= stopped.flags and not stopped.locked
        spin("strobe-test", 50.0)
        strobe.set_offset(20.0)                            # 20 Hz at 50 Hz: 2/3 revolution a flash
        clock.sleep(1.0)
        assert "offset_out_of_range" in strobe.wait_status().flags
        strobe.set_offset(0.5)
        strobe.lamp(False)
        clock.sleep(0.3)
        dark = strobe.wait_status()
        assert dark.flags == {"lamp_off"} and dark.strobe_hz == 0.0 and dark.apparent_hz is None
        with pytest.raises(ValueError):
            strobe.set_width(5000)                         # refused before anything is sent


def test_a_reset_strobe_gets_its_settings_again_and_says_so(clock):
    spin("strobe-test", 300.0)
    with open_strobe(clock, "&faults=reset_at:1.0", rate_hz=10, offset_hz=2.0) as strobe:
        clock.sleep(2.0)
        statuses = strobe.statuses_since(0.0)
        assert strobe.resets == 1
        assert [s for s in statuses if "reset" in s.flags]
        assert statuses[-1].apparent_hz == pytest.approx(2.0, abs=2e-4)   # not the default 0.5


def test_faults_name_the_device_and_command(clock):
    spin("strobe-test", 300.0)
    with pytest.raises(DeviceReplyError, match="OFFSET") as info:
        open_strobe(clock, "&faults=error_reply:1")
    assert "ERR busy" in str(info.value)
    with open_strobe(clock, "&faults=stop_at:2.0,garbage:0.3,split:0.5", rate_hz=10) as strobe:
        clock.sleep(1.0)
        assert strobe.wait_status().rotor_hz == pytest.approx(300.0, rel=1e-4)  # garbage is dropped
        clock.sleep(1.0)
        with pytest.raises(DeviceTimeout, match="strobe.*status"):
            strobe.wait_status(timeout=1.0)


def test_a_rig_with_a_strobe_role_on_sim(tmp_path):
    text = (REPO / "rigs" / "emulated-fig525.toml").read_text(encoding="utf-8")
    text += ('\n[devices.strobe]\nkind = "strobe"\nprotocol = "labkit_strobe"\n'
             'port = "sim://labkit_strobe?seed=4&plant=model-fig525&role=strobe"\n'
             'options = { offset_hz = 1.0, rate_hz = 10 }\n')
    (tmp_path / "rig.toml").write_text(text, encoding="utf-8")
    rig = load_rig(tmp_path / "rig.toml")
    assert rig.devices["strobe"].kind == "strobe"
    clock = VirtualClock()
    with use_emulation(), use_clock(clock):
        opened = open_rig(rig, clock)
        try:
            strobe, tach = opened.strobe("strobe"), opened.tachometer("rotor_tach")
            motor = opened.motors()["rotor_motor"]
            motor.enable()
            motor.set_duty(0.4)
            clock.sleep(4.0)
            rotor_hz = tach.wait_reading().value / TWO_PI
            status = strobe.wait_status()
            assert rotor_hz > 50 and status.rotor_hz == pytest.approx(rotor_hz, rel=0.01)
            assert status.apparent_hz == pytest.approx(1.0, abs=2e-3)
            with pytest.raises(KeyError, match="no open strobe called 'rotor_tach'"):
                opened.strobe("rotor_tach")
        finally:
            opened.close()


def test_labkit_probe_strobe(capsys):
    code = main(["probe", "strobe", "--protocol", "labkit_strobe", "--samples", "3", "--json",
                 "--port", "sim://labkit_strobe?plant=probe-strobe&seed=1&rate_hz=20",
                 "-o", "offset_hz=1.5", "-o", "rate_hz=20"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert json.loads(err.splitlines()[0])["model"] == "labkit-strobe"
    lines = [json.loads(line) for line in out.splitlines()]
    assert len(lines) == 3
    assert all(line["unit"] == "Hz" and "no_pulses" in line["flags"] for line in lines)  # nothing turns


def test_the_emulator_in_its_own_process_over_ptys(tmp_path):
    """``labkit emulate`` serves a motor and a strobe on one plant; the test drives the motor
    over its pty and the strobe, over its own, sees the rotor turn."""
    rig = tmp_path / "rig.toml"
    rig.write_text((REPO / "rigs" / "emulated-fig525.toml").read_text(encoding="utf-8") +
                   '\n[devices.strobe]\nkind = "strobe"\nprotocol = "labkit_strobe"\n'
                   'port = "sim://labkit_strobe?seed=4&plant=model-fig525&role=strobe&boot_s=0.05"\n',
                   encoding="utf-8")
    command = [sys.executable, "-m", "labkit", "emulate", str(rig), "--json", "--seconds", "20"]
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        paths = json.loads(proc.stdout.readline())
        clock = RealClock()
        smc = driver_class("motor", "pololu_smc")
        strobe_cls = driver_class("strobe", "labkit_strobe")
        with smc(open_port(paths["rotor_motor"], clock=clock, timeout=0, **smc.default_serial), clock,
                 name="rotor_motor", command_timeout_ms=500) as motor, \
                strobe_cls(open_port(paths["strobe"], clock=clock, timeout=0, **strobe_cls.default_serial),
                           clock, name="strobe", rate_hz=20, offset_hz=0.5) as strobe:
            motor.enable()
            motor.set_duty(0.3)
            clock.sleep(2.5)
            status = strobe.wait_status(timeout=2.0)
            assert status.rotor_hz > 20 and status.locked, status
            assert status.apparent_hz == pytest.approx(0.5, abs=0.05)   # the rotor still accelerates
    finally:
        proc.terminate()
        proc.wait(timeout=10)
