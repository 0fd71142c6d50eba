"""Motor cassettes recorded through record:// replay through replay:// strictly: the driver
writes the same bytes (keep-alive included) and reads the same statuses."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from labkit.devices.motor.scripted import run_motor_script
from labkit.devices.registry import driver_class
from labkit.errors import ReplayMismatch
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port

CASSETTES = Path(__file__).resolve().parents[2] / "recordings" / "cassettes"
SCRIPTS = {
    "motor-pololu_smc": ("pololu_smc", {"crc": True, "device_number": 13}),
    "motor-esc_bridge": ("esc_bridge", {}),
    "motor-vesc": ("vesc", {"pole_pairs": 7}),
}


def open_replay(name: str, mode: str = "strict"):
    protocol, options = SCRIPTS[name]
    clock = VirtualClock()
    port = open_port(f"replay://{CASSETTES / name}.jsonl?mode={mode}", clock=clock, timeout=0,
                     **driver_class("motor", protocol).default_serial)
    return port, clock, protocol, options


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_strict_replay_gives_identical_statuses(name):
    expected = json.loads((CASSETTES / f"{name}.expected.json").read_text(encoding="utf-8"))
    port, clock, protocol, options = open_replay(name)
    got = run_motor_script(port, clock, protocol, duty=0.3, run_s=1.0, **options)
    assert got["identify"] == expected["identify"]
    drop_t = [{k: v for k, v in s.items() if k != "t"} for s in got["statuses"]]
    assert drop_t == [{k: v for k, v in s.items() if k != "t"} for s in expected["statuses"]]
    assert expected["statuses"][-1]["value"] == pytest.approx(0.3, abs=1e-3)


def test_a_driver_that_writes_other_bytes_is_caught_by_strict_replay():
    port, clock, protocol, options = open_replay("motor-vesc")
    with pytest.raises(ReplayMismatch):
        run_motor_script(port, clock, protocol, duty=0.5, run_s=1.0, **options)
