"""Strobe cassettes (analysis/record_cassettes_strobe.py) replay through replay:// with the
status lines seen while recording: one recorded from the emulator on a virtual clock, one
from the sketch firmware/labkit_strobe running on simavr, over its pty on the real clock."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from labkit.devices.registry import driver_class
from labkit.devices.strobe.scripted import run_strobe_script
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port

CASSETTES = Path(__file__).resolve().parents[2] / "recordings" / "cassettes"
NAMES = ["strobe-labkit_strobe", "strobe-labkit_strobe-simavr"]
OPTIONS = {"offset_hz": 1.5, "width_us": 20, "rate_hz": 5}


def replay(name: str, mode: str) -> tuple[dict, dict]:
    expected = json.loads((CASSETTES / f"{name}.expected.json").read_text(encoding="utf-8"))
    clock = VirtualClock()
    port = open_port(f"replay://{CASSETTES / name}.jsonl?mode={mode}", clock=clock, timeout=0,
                     **driver_class("strobe", "labkit_strobe").default_serial)
    return run_strobe_script(port, clock, **OPTIONS), expected


@pytest.mark.parametrize("mode", ["strict", "timed"])
@pytest.mark.parametrize("name", NAMES)
def test_replay_gives_the_recorded_status_lines(name, mode):
    got, expected = replay(name, mode)
    assert got["identify"] == expected["identify"]
    keys = ("raw", "rotor_hz", "strobe_hz", "phase_deg", "flags", "divider", "apparent_hz", "stable")
    assert len(got["statuses"]) == len(expected["statuses"]) == 8
    for g, e in zip(got["statuses"], expected["statuses"], strict=True):
        assert {k: g[k] for k in keys} == {k: e[k] for k in keys}


@pytest.mark.parametrize("name", NAMES)
def test_the_recorded_strobe_showed_the_offset_it_was_given(name):
    """What the cassettes hold is itself right: once the settings of a window are the
    window's own (from its second line), f_rot - m * f_strobe is the 1.5 Hz asked for."""
    expected = json.loads((CASSETTES / f"{name}.expected.json").read_text(encoding="utf-8"))
    settled = expected["statuses"][1:4] + expected["statuses"][5:]
    assert {s["divider"] for s in settled} == {1, 2}
    for status in settled:
        assert status["stable"], status
        assert status["apparent_hz"] == pytest.approx(1.5, abs=5e-4), status
