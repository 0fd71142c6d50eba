"""The controllers' own watchdogs (issue 17, item 1): required by real-hardware rig files,
explained by `labkit probe motor`, emulated by the SMC emulator, on in the shipped emulated rigs."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.cli import main
from labkit.devices.motor.pololu_smc import CMD_EXIT_SAFE_START, format_command, speed_command
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.errors import RigFileError
from labkit.io.clock import VirtualClock, use_clock
from labkit.io.ports import open_port
from labkit.rig import bundled_rig_path, load_rig, parse_rig

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("template,key", [("template-balance.toml", "command_timeout_ms"),
                                          ("template-spin-critical.toml", "timeout_ms")])
def test_real_hardware_templates_declare_the_watchdog_and_are_refused_without_it(template, key):
    text = (REPO / "rigs" / template).read_text()
    rig = load_rig(REPO / "rigs" / template)
    assert float(rig.devices["rotor_motor"].options[key]) <= 1000
    without = "\n".join(line for line in text.splitlines() if not line.startswith("options = {"))
    with pytest.raises(RigFileError) as err:
        parse_rig(without, template)
    message = str(err.value)
    assert message.startswith(f"{template}:devices.rotor_motor.options.{key}: required for real hardware")
    assert "docs/explanation/safety.md" in message and "500" in message


@pytest.mark.parametrize("value,ok", [(500, True), (1000, True), (0, False), (50, False), (5000, False),
                                      ("nan", False)])
def test_watchdog_period_must_be_kept_alive_and_short(value, ok):
    text = (REPO / "rigs" / "template-balance.toml").read_text().replace(
        "options = { command_timeout_ms = 500 }", f"options = {{ command_timeout_ms = {value!r} }}")
    if ok:
        parse_rig(text, "rig.toml")
    else:
        with pytest.raises(RigFileError, match="options.command_timeout_ms"):
            parse_rig(text, "rig.toml")


def test_esc_bridge_needs_no_option_its_timeout_is_built_in():
    text = (REPO / "rigs" / "template-balance.toml").read_text().replace(
        'protocol = "pololu_smc"', 'protocol = "esc_bridge"').replace(
        "options = { command_timeout_ms = 500 }", "")
    assert parse_rig(text, "rig.toml").devices["rotor_motor"].protocol == "esc_bridge"


@pytest.mark.parametrize("name", ["emulated-fig525", "emulated-fig618"])
def test_shipped_emulated_rigs_turn_the_emulated_timeout_on_as_for_real_hardware(name):
    for path in (REPO / "rigs" / f"{name}.toml", bundled_rig_path(name)):
        motor = load_rig(path).devices["rotor_motor"]
        assert motor.options["command_timeout_ms"] == 500
        assert "command_timeout_ms=500" in motor.port


def test_emulated_smc_command_timeout_stops_the_motor_when_the_host_falls_silent():
    reset_plants()
    clock = VirtualClock()
    with use_clock(clock):
        port = open_port("sim://pololu_smc?plant=wd&command_timeout_ms=500", clock=clock, timeout=0.1)
        cmd, data = speed_command(1600)
        port.write(format_command(CMD_EXIT_SAFE_START, device_number=None))
        port.write(format_command(cmd, data))
        clock.sleep(0.4)
        motor = shared_plant("wd").motor("rotor")
        assert motor.duty == pytest.approx(0.5)   # still alive: 0.4 s < 0.5 s
        clock.sleep(0.2)                           # nothing sent since: the timeout fires at 0.5 s
        motor.advance(clock.now())
        assert motor.duty == 0.0
        assert motor.zeroed_since(0.0) == pytest.approx(0.5, abs=0.01)
        port.write(format_command(0xA1, bytes([0])))   # error status: bit 3 command timeout
        clock.sleep(0.05)
        assert int.from_bytes(port.read(2), "little") & 1 << 3
        port.close()
    reset_plants()


@pytest.mark.parametrize("protocol,expect", [
    ("pololu_smc", "Command timeout"), ("vesc", "App Settings > General > 'Timeout'"),
    ("esc_bridge", "built in")])
def test_probe_motor_says_how_to_enable_the_watchdog(capsys, protocol, expect):
    assert main(["probe", "motor", "--protocol", protocol, "--port", f"sim://{protocol}",
                 "--samples", "0"]) == 0
    notes = [line for line in capsys.readouterr().out.splitlines() if line.startswith("# watchdog:")]
    assert len(notes) == 1 and expect in notes[0]
