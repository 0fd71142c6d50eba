"""A lying tachometer and a stalled motor, injected at the emulator in its own process (issue 29).

`labkit emulate` serves the shipped emulated Fig. 5.25 rig; `labkit run` drives it over its
pseudo-terminals with the limit lowered to 12 000 RPM, recording at 8 000 RPM. Once the step
has settled, SIGUSR2 to `labkit emulate` starts the fault. The emulator's own log of the true
rotor speed and duty (``--truth``) says what the rotor did, whatever its tachometer said.

Acceptance (docs/explanation/safety.md, "Sensor faults"): the interlock within 2 s of the fault (a
stalled motor: within 3 s of the duty saturating), a message naming the device and the
numbers, the true rotor never above the limit, no point recorded, exit non-zero.
"""

from __future__ import annotations

import json
import sys

import pytest

from .harness import EmulatedRig

pytestmark = [pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ptys, /proc"),
              pytest.mark.timeout(120)]

LIMIT_RPM = 12000.0
STEP_RPM = 8000.0
CAP_DUTY = LIMIT_RPM / 23873  # duty * full_speed_rpm at the limit
EDITS = (("max_speed_rpm = 24000", f"max_speed_rpm = {LIMIT_RPM:.0f}"),
         # a silent tachometer within 1 s (the harness's 2 s is for a loaded box; 1 s still is)
         ("tach_timeout_s = 2.0", "tach_timeout_s = 1.0"))


def run_with_fault(tmp_path, fault: str) -> dict:
    """Hold 8 000 RPM, start ``fault`` (ROLE:NAME) once settled; what happened, in numbers."""
    with EmulatedRig(tmp_path, fault_on_usr2=(fault,), truth=True, pty_rig_edits=EDITS) as lab:
        run = lab.start_run(tmp_path / "sessions", record_s=30.0, speed_rpm=STEP_RPM)
        run.wait_event("settled")
        sent = lab.inject_fault()
        stderr = run.finish(timeout=60)
        events = run.events()
        truth = lab.true_motor()
    interlock = next((e for e in events if e["type"] == "interlock"), None)
    after = [s for s in truth if s["t"] >= sent]
    zeroed = next((s["t"] for s in after if s["duty"] == 0.0), None)
    saturated = next((s["t"] for s in after if s["duty"] >= CAP_DUTY - 1e-3), None)
    results = [e for e in events if e["type"] == "results"]
    outcome = {
        "fault": fault, "sent": sent, "stderr": stderr, "returncode": run.proc.returncode,
        "interlock": interlock, "trip_s": interlock["t"] - sent if interlock else None,
        "zeroed_s": zeroed - sent if zeroed is not None else None,
        "saturated_s": saturated - sent if saturated is not None else None,
        "peak_rpm": max(s["rpm"] for s in truth), "points": [e for e in events if e["type"] == "point"],
        "result_points": results[-1]["results"]["points"] if results else None,
    }
    shown = ("fault", "trip_s", "zeroed_s", "saturated_s", "peak_rpm", "returncode")
    print("sensor fault:", json.dumps({k: v for k, v in outcome.items() if k in shown}))
    print(stderr.strip().splitlines()[0] if stderr.strip() else "(no stderr)")
    return outcome


def assert_stopped_safely(outcome: dict, within_s: float, words: list[str]) -> None:
    assert outcome["interlock"] is not None, outcome["stderr"]
    assert outcome["trip_s"] <= within_s, f"interlock {outcome['trip_s']:.2f} s after the fault"
    assert outcome["zeroed_s"] is not None and outcome["zeroed_s"] <= within_s + 0.2, outcome["zeroed_s"]
    assert outcome["peak_rpm"] <= LIMIT_RPM, f"true rotor at {outcome['peak_rpm']:.0f} RPM"
    assert outcome["points"] == [] and not outcome["result_points"], "a point from the faulty window"
    assert outcome["returncode"] not in (0, None)
    assert "Traceback" not in outcome["stderr"], outcome["stderr"]
    for word in words:
        assert word in outcome["stderr"], outcome["stderr"]


def test_tachometer_reading_zero_mid_step_stops_the_run(tmp_path):
    outcome = run_with_fault(tmp_path, "rotor_tach:zero")
    assert_stopped_safely(outcome, 2.0, ["tachometer rotor_tach implausible", "reads 0 RPM",
                                         "rotor_motor", "predicts at least"])


def test_tachometer_stuck_mid_step_stops_the_run(tmp_path):
    outcome = run_with_fault(tmp_path, "rotor_tach:stuck")
    assert_stopped_safely(outcome, 2.0, ["tachometer rotor_tach stuck", "the same value", "RPM"])


def test_tachometer_repeating_its_last_line_mid_step_stops_the_run(tmp_path):
    # the same line, sequence number and all: no new reading, so the tachometer is silent
    outcome = run_with_fault(tmp_path, "rotor_tach:repeat")
    assert_stopped_safely(outcome, 2.0, ["tachometer rotor_tach silent for"])


def test_tachometer_frozen_mid_step_stops_the_run(tmp_path):
    outcome = run_with_fault(tmp_path, "rotor_tach:stop")
    assert_stopped_safely(outcome, 2.0, ["tachometer rotor_tach silent for"])


def test_stalled_motor_stops_the_run_within_3_s_of_the_duty_saturating(tmp_path):
    outcome = run_with_fault(tmp_path, "rotor_motor:stall")
    assert outcome["saturated_s"] is not None, "the loop never saturated its duty into the stall"
    assert outcome["interlock"] is not None and outcome["trip_s"] - outcome["saturated_s"] <= 3.0
    assert_stopped_safely(outcome, 3.0, ["rotor_motor", "saturated"])
