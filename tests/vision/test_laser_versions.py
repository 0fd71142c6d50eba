"""Laser analysis version 2 (ADR 0040; the change itself measured in ADR 0039): the fit's refits
from a fit already close to its points (the wander's rounds, the ellipse's polish on every trace
pixel) start from the fit's drift and stop once the curve settles (``SETTLE_PX``), where version
1 ran a fixed number of steps from zero drift. Its answers on the shipped clips stay within the
stated accuracy of the laser analysis (labkit/vision/laser/version.py: what a replay holds a
session made by version 1 to), half of what the example tests accept against the ground truth
(tests/vision/test_examples.py), and every verdict, pattern and loop count stays. Version 1's
answers are in laser_answers_v1.json."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from labkit.vision.laser.analyse import analyse_laser
from labkit.vision.laser.pattern_fit import SETTLE_PX, fit_ellipse, polish
from labkit.vision.laser.version import LASER_ANALYSIS

HERE = Path(__file__).resolve().parent
VIDEOS = HERE.parents[1] / "recordings" / "videos"
BEFORE = json.loads((HERE / "laser_answers_v1.json").read_text())
CLIPS = sorted(k for k in BEFORE if not k.startswith("_"))

CENTRE_PX = LASER_ANALYSIS.accuracy["centre"].abs  # 0.5: the examples accept 1 px from the truth
SEMI_AXIS_REL = LASER_ANALYSIS.accuracy["semi_axes"].rel  # 1 % (the examples 2 %), or CENTRE_PX
ELLIPTICITY_ABS = 0.01  # 0.02
TROCHOID_B_ABS = 0.025  # 0.05
TILT_REL = LASER_ANALYSIS.accuracy["tilt"].rel  # 1 %: atan(semi-axis x scale / distance) / 2
SCALE_MM_PER_PX, DISTANCE_MM = 0.4, 500.0
CURVE_MOVE_PX = 0.5  # a change of rotation may move the curve's points by at most this much
LANDS_PX = 0.005  # a settled refit and a 40-step one agree to this (5 x SETTLE_PX)


def rotation_moves_px(before: dict, now: dict) -> float:
    """How far a change of rotation moves the curve's points: by the angle times the
    semi-axes' difference for an ellipse (a circle's rotation moves nothing), times the largest
    radius for a trochoid."""
    turn = math.radians(abs((now["rotation_deg"] - before["rotation_deg"] + 90) % 180 - 90))
    major, minor = before["semi_axes_px"]
    return turn * (major if before["trochoid_b"] is not None else major - minor)


def test_the_version_was_bumped():
    assert LASER_ANALYSIS.version == 3  # 3: the wander's rounds iterate to a tolerance (ADR 0043)


@pytest.mark.parametrize("name", CLIPS)
def test_shipped_clips_answer_as_version_1_within_the_stated_accuracy(name):
    before = BEFORE[name]
    r = analyse_laser(str(VIDEOS / name), screen_distance_mm=DISTANCE_MM, mm_per_px=SCALE_MM_PER_PX).to_json()
    p, q = r["pattern"], r["quality"]
    now = {"verdict": q["verdict"], "reasons": q["reasons"], "type": p["type"], "loops": p["loops"],
           "symmetry": p["symmetry"], "rotation_deg": p["rotation_deg"], "semi_axes_px": p["semi_axes_px"],
           "trochoid_b": None if p["trochoid"] is None else p["trochoid"]["b"]}
    for key in ("verdict", "reasons", "type", "loops", "symmetry"):
        assert now[key] == before[key], (name, key)
    assert math.dist(p["center_px"], before["center_px"]) <= CENTRE_PX
    for now_px, before_px in zip(p["semi_axes_px"], before["semi_axes_px"], strict=True):
        assert abs(now_px - before_px) <= max(CENTRE_PX, SEMI_AXIS_REL * before_px)
    if before["ellipticity"] is not None:
        assert p["ellipticity"] == pytest.approx(before["ellipticity"], abs=ELLIPTICITY_ABS)
    if before["trochoid_b"] is not None:
        assert now["trochoid_b"] == pytest.approx(before["trochoid_b"], abs=TROCHOID_B_ABS)
    for axis in ("major", "minor"):
        # (or the tilt that CENTRE_PX of semi-axis makes, d tilt = d r S / (2 L) for small tilts)
        assert r["tilt_rad"][axis] == pytest.approx(before["tilt_rad"][axis], rel=TILT_REL,
                                                    abs=CENTRE_PX * SCALE_MM_PER_PX / (2 * DISTANCE_MM))
    assert rotation_moves_px(before, now) <= CURVE_MOVE_PX


def drifting_ellipse(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Noisy points of an ellipse whose centre drifts 3 px/s over 4 s, and their times."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 4, 3000)
    phase = rng.uniform(0, 2 * math.pi, len(t))
    z = (200 + 150j) + 3 * (t - 2) * (0.8 + 0.6j) + 90 * np.cos(phase) + 1j * 55 * np.sin(phase)
    z = (z - (200 + 150j)) * np.exp(0.4j) + (200 + 150j)
    z += rng.normal(0, 0.7, len(t)) + 1j * rng.normal(0, 0.7, len(t))
    return np.column_stack([z.real, z.imag]), t


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_settled_refit_lands_where_a_long_refit_does(seed):
    points, times = drifting_ellipse(seed)
    start = fit_ellipse(points[:300], times=times[:300], iterations=2)  # close, not converged
    settled = polish(start, points, None, times, 40, SETTLE_PX)
    long = polish(start, points, None, times, iterations=40)  # from zero drift, 40 steps
    for name in ("c", "drift"):  # (a, b themselves turn with the curve parameter's origin)
        assert abs(getattr(settled, name) - getattr(long, name)) < LANDS_PX, name
    assert settled.pattern.semi_axes == pytest.approx(long.pattern.semi_axes, abs=LANDS_PX)
    assert settled.pattern.rotation_rad == pytest.approx(long.pattern.rotation_rad, abs=1e-4)
    assert settled.rms_residual == pytest.approx(long.rms_residual, abs=LANDS_PX)
