"""The stroboscope body driven by labkit.sim (labkit.footage.sim_swing): checked against the
model's steady state (labkit.model via labkit.predict), then rendered and analysed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.footage.sim_swing import SimulatedSwing, SimulatedSwingError
from labkit.footage.suite import suite_cases
from labkit.footage.suite_build import build_shot
from labkit.footage.suite_eval import evaluate_case
from labkit.predict.magnets import parse_magnet_spec
from labkit.predict.pair import ForceCurve, Pair


def _steady_state(swing: SimulatedSwing):
    pair = Pair(parse_magnet_spec(swing.rotator), parse_magnet_spec(swing.floator),
                math.radians(swing.tilt_deg))
    curve = ForceCurve(pair, 2 * math.pi * swing.rotor_hz)
    return curve.state(curve.bound_state().r_eq)


def test_simulated_motion_is_the_models_cone_and_lateral_circle():
    swing = SimulatedSwing(rotor_hz=250.0, mm_per_px=0.1)
    state = _steady_state(swing)
    # the side view's tilt amplitude is the cone angle (first harmonic: within its third harmonic)
    assert swing.phi_rad == pytest.approx(state.phi, rel=5e-3)
    assert swing.beta_px == pytest.approx(state.beta * 1e3 / 0.1, rel=1e-3)
    assert abs(swing.delta_px) == pytest.approx(swing.beta_px / math.tan(swing.phi_rad), rel=1e-9)
    # Eq. 5.97: the centre of mass swings in phase (or anti-phase) with the tilt
    assert min(abs(swing.lag_rad), abs(abs(swing.lag_rad) - math.pi)) < 1e-3
    t = np.linspace(0.0, 3 / swing.rotor_hz, 301)
    assert np.allclose(swing.tilt(t), swing.tilt(t + 1 / swing.rotor_hz), atol=1e-9)  # rotor-periodic
    assert np.max(np.abs(swing.tilt(t))) == pytest.approx(state.phi, rel=5e-3)


def test_a_faster_rotor_closes_the_cone():
    slow, fast = SimulatedSwing(rotor_hz=200.0), SimulatedSwing(rotor_hz=400.0)
    assert fast.phi_rad < slow.phi_rad  # phi falls with omega (Eq. 5.24)


def test_a_pair_that_does_not_bind_is_refused():
    with pytest.raises(SimulatedSwingError, match="not bound"):
        _ = SimulatedSwing(floator="sphere:10mm", tilt_deg=10.0, rotor_hz=25000 / 60).phi_rad


def test_suite_holds_simulated_strobe_cases_with_model_truth():
    sim = [c for c in suite_cases(only="strobe") if c.source == "sim"]
    assert len(sim) >= 12 and {c.body for c in sim} == {"cylinder", "cuboid"}
    shot = build_shot(sim[0])
    assert isinstance(shot.swing, SimulatedSwing)
    assert 0.05 < shot.swing.phi_rad < 0.2 and shot.swing.beta_px > 1.0


@pytest.mark.parametrize("name", ["strobe-sim-cuboid-03-easy", "strobe-sim-cylinder-06-easy"])
def test_simulated_strobe_clip_is_measured_within_tolerance(name, tmp_path):
    case = next(c for c in suite_cases(only="strobe") if c.name == name)
    outcome = evaluate_case(case, tmp_path)
    assert outcome.passed, (outcome.failures, outcome.errors, outcome.verdict)
