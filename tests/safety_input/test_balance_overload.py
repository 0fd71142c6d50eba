"""Issue 17, deliver 9: a balance overload during a step ends the run with one line naming the
balance, the speed and the overload, recorded as the run's stop reason, motors at zero. Over the
real protocol path: the emulated MT-SICS balance with a 10 g capacity, which the PFR force of
the emulated Fig. 5.25 rig (about 15 g at 6000 RPM) exceeds."""

from __future__ import annotations

import json
import math

import pytest

from labkit.emulators.plant import shared_plant
from labkit.errors import LabkitError
from labkit.protocols.speed_sweep import mean_stderr

from .conftest import rig_with, run_cli


def test_overload_during_a_step_is_one_line_and_the_stop_reason(tmp_path, capsys):
    where = "seed=3&plant=model-fig525&role=balance"
    rig = rig_with(tmp_path, where, where + "&capacity_g=10")
    root = tmp_path / "sessions"
    code, out, err = run_cli(["run", rig, "speed-sweep", "--sessions", root, "--no-progress",
                              "--set", "speeds_rpm=6000,12000", "--set", "record_s=1.0"], capsys)
    assert code == 2 and "Traceback" not in err and "numerator" not in err
    (first,) = [line for line in err.splitlines() if " failed: " in line]   # other lines: warnings, hint
    assert first.startswith("labkit run: failed: balance: balance overload at 6")
    assert "RPM (capacity" in first and "motors at zero" in first
    (session,) = root.iterdir()
    meta = json.loads((session / "run.json").read_text())
    assert meta["status"] == "failed" and "balance overload at 6" in meta["reason"]
    events = [json.loads(line) for line in (session / "events.jsonl").read_text().splitlines()]
    assert not [e for e in events if e["type"] == "point"]       # no point from overloaded readings
    motor = shared_plant("model-fig525").motor("rotor")
    assert motor.duty_changes and motor.duty_changes[-1][1] == 0.0  # the last command was zero


def test_mean_of_readings_with_a_nan_is_an_error_not_a_point():
    with pytest.raises(LabkitError, match="1 of 3 readings are not numbers"):
        mean_stderr([1.0, math.nan, 2.0])
    mean, stderr = mean_stderr([1.0, 3.0])
    assert mean == pytest.approx(2.0) and stderr == pytest.approx(1.0)
