"""Tachometer cassettes recorded through record:// (analysis/record_cassettes_tach_motor.py)
replay through replay:// with exactly the readings seen while recording."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from labkit.devices.registry import driver_class
from labkit.devices.tachometer.scripted import run_tach_script
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port

CASSETTES = Path(__file__).resolve().parents[2] / "recordings" / "cassettes"
SCRIPTS = {"tach-labkit_tach": ("labkit_tach", {"ppr": 2}), "tach-lutron16": ("lutron16", {}),
           "tach-monarch_at": ("monarch_at", {})}


def same(a, b) -> bool:
    """Equality that treats NaN (an over-range reading) as equal to NaN."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def replay(name: str, mode: str) -> tuple[dict, dict]:
    protocol, options = SCRIPTS[name]
    expected = json.loads((CASSETTES / f"{name}.expected.json").read_text(encoding="utf-8"))
    clock = VirtualClock()
    port = open_port(f"replay://{CASSETTES / name}.jsonl?mode={mode}", clock=clock, timeout=0,
                     **driver_class("tachometer", protocol).default_serial)
    return run_tach_script(port, clock, protocol, duration_s=2.0, **options), expected


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_strict_replay_gives_identical_readings(name):
    got, expected = replay(name, "strict")
    assert got["identify"] == expected["identify"]
    keys = ("value", "unit", "stable", "overload", "flags", "raw")
    assert len(got["readings"]) == len(expected["readings"]) > 0
    for g, e in zip(got["readings"], expected["readings"], strict=True):
        assert all(same(g[k], e[k]) for k in keys), (g, e)


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_timed_replay_on_a_virtual_clock_also_keeps_the_times(name):
    got, expected = replay(name, "timed")
    assert [r["t"] for r in got["readings"]] == pytest.approx([r["t"] for r in expected["readings"]])
    assert [r["raw"] for r in got["readings"]] == [r["raw"] for r in expected["readings"]]
