"""Failure classes of issue 11 on footage labkit's analysis was not tuned on: cases of the
independent renderer's robustness suite (labkit.footage) and hard labkit.synth clips. Each case
failed on the analysis before issue 11 (noted per test) and is held here to the suite's
tolerances; a result outside them must not be called ``ok``."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from labkit.footage.suite import suite_cases
from labkit.footage.suite_eval import render_case, score_laser
from labkit.synth import laser_truth, render_laser, write_clip
from labkit.synth.presets import laser_pattern, laser_preset
from labkit.vision.laser.analyse import analyse_laser

SUITE = {c.name: c for c in suite_cases(None, None, None)}


@pytest.fixture(scope="module")
def suite_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("suite")


@pytest.mark.parametrize("name", [
    # a timestamp burnt into the corner: read as a 3-loop epitrochoid 103 px off centre
    "circle-01-medium",
    "ellipse-05-medium",
    # a camera drifting at 7 px/s and wandering on its tripod (short clip): an ellipse 26 px off
    "circle-08-hard",
    # a 12 px saturated line filling a 6-loop epitrochoid on 320x240: the pattern's glow raised the
    # background inside it, the inner loops fell under the noise floor and only the outer rim was
    # found (read as an ellipse, doubtful); found since the trace continues a line (hysteresis)
    "epitrochoid-6-04-hard",
])
def test_independent_footage_within_tolerance_and_ok(suite_cache, name):
    path, truth = render_case(SUITE[name], suite_cache)
    result = analyse_laser(str(path))
    failures, errors = score_laser(result.to_json(), truth)
    assert failures == [], errors
    assert result.quality.verdict == "ok", result.quality.reasons


def test_arcs_beside_a_larger_timestamp_read_right_and_say_what_was_left_out(suite_cache):
    """8 separate arcs of 0.1 cycle (80 % of the curve never lit), a camera drifting 22 px, and a
    timestamp larger than every arc: the timestamp was taken for the pattern (an ellipse 472 px
    off). The timestamp stays at the same pixels while the pattern moves, so it is not on the
    screen. The result stays doubtful (most of the curve extrapolated, drift assumed straight)."""
    path, truth = render_case(SUITE["hypotrochoid-4-06-medium"], suite_cache)
    result = analyse_laser(str(path))
    failures, errors = score_laser(result.to_json(), truth)
    assert failures == [], errors
    q = result.quality
    assert q.evidence["light_fixed_in_frame"] > 0.3
    assert q.verdict == "doubtful" and any("extrapolated" in r for r in q.reasons)


def _synth(tmp_path, size, level, seed, kind, loops, b, arc, cycle_hz=9.0, **extra):
    spec = laser_preset(level, size, seed=seed)
    spec = replace(spec, pattern=laser_pattern(kind, size, loops=loops, b=b, rotation_deg=17), frames=45,
                   cycle_hz=cycle_hz, exposure_s=arc / cycle_hz, **extra)
    truth = laser_truth(spec)
    path = write_clip(tmp_path / f"{kind}{loops}.mp4", render_laser(spec), spec.fps, "mp4v", truth)
    return analyse_laser(str(path)), truth["pattern"]


def _judge(result: dict, want: dict, b_tolerance: float = 0.05) -> None:
    got, q = result.pattern, result.quality
    assert (got.type, got.loops, got.symmetry) == (want["type"], want["loops"],
                                                            round(1 / abs(want["trochoid"]["a"])))
    assert abs(got.semi_axes_px[0] / want["semi_axes_px"][0] - 1) < 0.02
    assert math.dist(got.center_px, want["center_px"]) < 0.01 * 2 * want["semi_axes_px"][0]
    b_error = abs(got.trochoid.b - want["trochoid"]["b"])
    assert b_error < 2 * b_tolerance
    if b_error > b_tolerance:  # outside the tolerance: the verdict must not say ok
        assert q.verdict != "ok"


def test_six_loop_epitrochoid_in_short_arcs_is_not_read_as_a_hypotrochoid(tmp_path):
    """0.4 of a cycle per frame, hard footage (halo, noise, lamp, drift): read as a 5-loop
    hypotrochoid before the trochoid starts were spread over loop shape (|k| b)."""
    result, want = _synth(tmp_path, (640, 480), "hard", 501, "epitrochoid", 6, 0.3, 0.4, cycle_hz=7.71)
    _judge(result, want)


def test_seven_loop_epitrochoid_under_a_rolling_shutter(tmp_path):
    """1280x720, a 30 ms rolling-shutter readout, 0.5 of a cycle per frame: read as a 6-loop
    hypotrochoid before. The halo fills the tiny loops, so b may read high
    (docs/explanation/laser-analysis.md, What labkit cannot see): beyond the issue's 0.05 the verdict must not
    be ok."""
    result, want = _synth(tmp_path, (1280, 720), "hard", 513, "epitrochoid", 7, 0.25, 0.5,
                          rolling_shutter_s=0.03)
    _judge(result, want)
