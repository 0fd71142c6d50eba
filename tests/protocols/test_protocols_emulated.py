"""The two protocols on their emulated rigs recover the plants' physics."""

import json
from pathlib import Path

import pytest

from labkit.emulators.break_up import break_up
from labkit.emulators.rig_plant import SpinCriticalLaw
from labkit.emulators.twin_model import force_g, params_from_rig
from labkit.errors import LabkitError, RigFileError, SafetyError
from labkit.protocols.launch import execute, prepare_run
from labkit.protocols.quickfit import quick_fit_power_law
from labkit.rig import load_rig

RIGS = Path(__file__).resolve().parents[2] / "rigs"


def test_speed_sweep_recovers_the_emulated_exponent(tmp_path):
    prep = prepare_run(RIGS / "emulated-fig525.toml", "speed-sweep",
                       ["speeds_rpm=6000:20000:2000", "record_s=1.0", "zero=start"], session_root=tmp_path)
    outcome = execute(prep, tmp_path)
    assert outcome.status == "completed"
    results = json.loads((outcome.session / "results.json").read_text())
    assert results["protocol"] == "speed-sweep"
    assert len(results["points"]) == 8
    b = results["fit"]["params"]["b"]
    # the model plant (plant=model-fig525): the PFR of the rig's magnets (about w^-2)
    params = params_from_rig(load_rig(RIGS / "emulated-fig525.toml"))
    model = [force_g(params, p["speed_rad_s"]) for p in results["points"]]
    model_b = quick_fit_power_law([p["speed_rpm"] for p in results["points"]], model)["params"]["b"]["value"]
    assert b["value"] == pytest.approx(model_b, abs=0.01)
    assert -2.1 <= b["value"] <= -1.7 and b["stderr"] > 0
    for point, expected_g in zip(results["points"], model, strict=True):
        assert point["speed_rpm"] == pytest.approx(point["target_rpm"], rel=0.01)
        assert point["force_g"] == pytest.approx(expected_g, rel=0.01)
        assert point["n"] >= 5


def test_spin_critical_pairs_follow_the_plant_law(tmp_path):
    prep = prepare_run(RIGS / "emulated-fig618.toml", "spin-critical",
                       ["start_rpm=6600", "stop_rpm=11000", "step_pct=15", "max_trials=3"],
                       session_root=tmp_path)
    outcome = execute(prep, tmp_path)
    assert outcome.status == "completed", outcome.reason
    # the model-fig618 plant: C of Eq. 6.37 from the rig's magnets, 1 % threshold noise
    c_model = break_up(params_from_rig(load_rig(RIGS / "emulated-fig618.toml"))).c
    law = SpinCriticalLaw(c=c_model)
    points = outcome.results["points"]
    assert len(points) == 4
    for p in points:
        assert not p["no_drop"]
        expected = law.critical_spin(p["rotor_rad_s"])
        # the plant draws the drop spin with 1 % noise: 3 sigma
        assert p["spin_rad_s"] == pytest.approx(expected, rel=0.03, abs=15), p
        assert p["k"] == pytest.approx(p["spin_rad_s"] / p["rotor_rad_s"] - 1)
    c = outcome.results["fit"]["params"]["C"]
    # no bias: the plant's C lies inside the fit's 95 % interval (registering the last
    # tachometer line before the drop put it 3 stderr above)
    assert abs(c["value"] - c_model) <= 2 * c["stderr"], c
    drops = [json.loads(line) for line in (outcome.session / "events.jsonl").read_text().splitlines()]
    assert any(e["type"] == "drop" and e["cause"] == "balance" for e in drops)


def test_dry_run_plan_lists_steps_and_checks_limits():
    prep = prepare_run(RIGS / "emulated-fig525.toml", "speed-sweep", ["speeds_rpm=6000,12000"],
                       session_root=None)
    text = prep.runner.dry_run()
    assert "2 steps" in text and "12000 RPM" in text and "limit 24000 RPM" in text


@pytest.mark.parametrize("rig, protocol, sets, error, message", [
    ("emulated-fig525.toml", "speed-sweep", ["speeds_rpm=20000:30000:5000"], SafetyError,
     "asks 25000 RPM, above the rig's limit of 24000 RPM"),
    ("emulated-fig525.toml", "spin-critical", [], RigFileError,
     "spin-critical needs a tachometer device called 'floator_tach'"),
    ("emulated-fig525.toml", "levitate", [], LabkitError, "unknown protocol 'levitate'"),
    ("emulated-fig525.toml", "speed-sweep", ["speed=5"], LabkitError, "--set speed: unknown parameter"),
    ("emulated-fig525.toml", "speed-sweep", ["speeds_rpm=fast"], LabkitError, "is not a number"),
])
def test_bad_plans_are_refused_before_anything_opens(rig, protocol, sets, error, message):
    with pytest.raises(error, match=None) as info:
        prepare_run(RIGS / rig, protocol, sets, session_root=None)
    assert message in str(info.value)


def test_spin_critical_detects_the_drop_by_spin_loss_when_the_balance_is_slow(tmp_path):
    # a balance answering 0.8 s late, a spin tachometer reporting zero 0.2 s after its target goes
    text = (RIGS / "emulated-fig618.toml").read_text()
    text = text.replace("role=balance", "role=balance&faults=delay:0.8")
    text = text.replace("source=floator", "source=floator&zto_ms=200")
    rig = tmp_path / "slow-balance.toml"
    rig.write_text(text)
    sets = ["start_rpm=6600", "stop_rpm=8000", "step_pct=15", "max_trials=2"]
    prep = prepare_run(rig, "spin-critical", sets, session_root=tmp_path / "s")
    outcome = execute(prep, tmp_path / "s")
    assert outcome.status == "completed", outcome.reason
    law = SpinCriticalLaw()
    trials = [t for p in outcome.results["points"] for t in p["trials"]]
    assert len(trials) == 4 and {t["cause"] for t in trials} == {"spin_loss"}
    for t in trials:
        assert t["spin_rad_s"] == pytest.approx(law.critical_spin(t["rotor_rad_s"]), rel=0.03, abs=15)
