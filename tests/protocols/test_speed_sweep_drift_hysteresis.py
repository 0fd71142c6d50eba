"""speed-sweep on the emulated Fig. 5.25 rig: drift correction (zero=each) and the
hysteresis/repeat plan (up_down, repeats), through the protocol runner on a virtual clock."""

import math
from pathlib import Path

import pytest

from labkit.emulators.twin_model import TwinParams, force_g
from labkit.protocols.launch import execute, prepare_run

RIGS = Path(__file__).resolve().parents[2] / "rigs"
DRIFT_G_PER_S = 0.05   # a badly drifting balance: ~1 g over the run, a quarter of the 14000 RPM force


def law_g(rpm: float) -> float:
    """The model plant's balance force (docs/explanation/twin.md): grams force at ``rpm``."""
    return force_g(TwinParams(), rpm * math.pi / 30.0)


def sweep(tmp_path, name: str, sets: list[str]) -> dict:
    text = (RIGS / "emulated-fig525.toml").read_text()
    assert "role=balance" in text
    rig = tmp_path / f"{name}.toml"
    rig.write_text(text.replace("role=balance", f"role=balance&drift_g_per_s={DRIFT_G_PER_S}"))
    prep = prepare_run(rig, "speed-sweep", ["speeds_rpm=6000,10000,14000", "record_s=1.0", *sets],
                       session_root=tmp_path / name)
    outcome = execute(prep, tmp_path / name)
    assert outcome.status == "completed", outcome.reason
    return outcome.results


def test_rest_readings_remove_a_drifting_zero_and_up_down_repeats_follow_the_plan(tmp_path):
    results = sweep(tmp_path, "each", ["zero=each", "up_down=true", "repeats=2"])
    points = results["points"]
    plan = [("up", 6000.0), ("up", 10000.0), ("up", 14000.0), ("down", 10000.0), ("down", 6000.0)]
    assert [(p["direction"], p["target_rpm"]) for p in points] == plan * 2
    assert [p["repeat"] for p in points] == [0] * 5 + [1] * 5
    for p in points:
        assert p["force_g"] == pytest.approx(law_g(p["speed_rpm"]), rel=0.02), p
    # the rest readings saw the drift grow through the run (N, positive: the zero creeps up)
    drifts = [p["drift_n"] for p in points]
    assert drifts == sorted(drifts) and drifts[-1] > 5 * drifts[0] > 0
    # hysteresis: the same speed up and down reads the same force (the emulator has none)
    assert points[1]["force_g"] == pytest.approx(points[3]["force_g"], rel=0.02)
    # the model's PFR at these speeds falls as w^-2.005 (ln(F(6000)/F(14000)) / ln(14/6))
    model_b = -math.log(law_g(6000.0) / law_g(14000.0)) / math.log(14000.0 / 6000.0)
    assert results["fit"]["params"]["b"]["value"] == pytest.approx(model_b, abs=0.02)


def test_without_rest_readings_the_same_drift_biases_the_forces(tmp_path):
    # the control experiment: zeroing once at the start leaves the drift in the forces
    points = sweep(tmp_path, "start", ["zero=start", "up_down=true"])["points"]
    worst = max(abs(p["force_g"] / law_g(p["speed_rpm"]) - 1) for p in points)
    assert worst > 0.1
