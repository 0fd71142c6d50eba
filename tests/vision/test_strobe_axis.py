"""The strobe body's axis on small blurred bodies, and the verdict when a faint ambient ghost makes
the tilt depend on how it is handled (issue 11, renderer version 3: lens blur of the body).

The body is drawn here with its own supersampled polygon fill and a Gaussian lens, gamma-encoded
like a camera's output; nothing is shared with labkit's generators."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from strobe_scenes import Scene, write

from labkit.vision.strobe.analyse import analyse_strobe
from labkit.vision.strobe.body import measure_body
from labkit.vision.strobe.checks import strobe_quality

SUPER = 8


def _given(s: Scene) -> dict:
    return {"rotor_hz": s.rotor_hz, "strobe_hz": s.strobe_hz}


def _blurred_bar(angle: float, centre: tuple[float, float], length: float, width: float,
                 sigma: float) -> np.ndarray:
    """Dark bar (axis at ``angle`` from image +x) on a bright 240x240 background, lens-blurred and
    gamma-encoded (1/2.2) into 8 bits."""
    u = np.array([math.cos(angle), math.sin(angle)]) * length / 2
    v = np.array([-math.sin(angle), math.cos(angle)]) * width / 2
    c = np.asarray(centre)
    corners = np.array([c + u + v, c + u - v, c - u - v, c - u + v])
    big = np.zeros((240 * SUPER, 240 * SUPER), np.uint8)
    cv2.fillPoly(big, [np.round(((corners + 0.5) * SUPER - 0.5) * 16).astype(np.int32)], 255, cv2.LINE_8, 4)
    cover = cv2.resize(big.astype(np.float32) / 255.0, (240, 240), interpolation=cv2.INTER_AREA)
    linear = 0.55 - 0.5 * cv2.GaussianBlur(cover, (0, 0), sigma)
    return (linear ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)


@pytest.mark.parametrize("sigma", [0.8, 1.5, 2.2])
@pytest.mark.parametrize("angle", [-math.pi / 2 + 0.07, -math.pi / 2 - 0.16, 0.11])
def test_linear_moments_keep_a_small_blurred_bars_axis(sigma, angle):
    """A 30 x 14 px bar (half diagonal 16.6 px) blurred by up to 2.2 px: the axis from the moments
    linear in intensity stays within 0.1 px at the bar's ends (the tilt-resolution check's
    assumption for ghost-free clips)."""
    length, width = 30.0, 14.0
    radius = 0.5 * math.hypot(length, width)
    pose = measure_body(_blurred_bar(angle, (120.3, 119.6), length, width, sigma))
    assert pose is not None and pose.linear is not None
    error_px = abs(math.remainder(pose.linear[0] - angle, math.pi)) * radius
    assert error_px < 0.1


def test_clean_clip_uses_linear_moments_and_a_faint_ghost_is_taken_out(tmp_path):
    clean = Scene(seed=31)
    r = analyse_strobe(write(clean, tmp_path / "clean.avi"), **_given(clean))
    assert r.quality.evidence["axis_method"] == "linear moments" and r.room_light is None
    faint = Scene(ghost=0.12, seed=32)
    r = analyse_strobe(write(faint, tmp_path / "faint.avi"), **_given(faint))
    assert 0.01 < r.quality.evidence["ghost_fraction"] <= 0.08
    assert r.quality.evidence["axis_method"] == "linear moments, room light taken out"
    assert r.tilt_amplitude_rad == pytest.approx(faint.phi_rad, rel=0.05)


def _evidence(tmp_path) -> dict:
    s = Scene(seed=33)
    q = analyse_strobe(write(s, tmp_path / "base.avi"), **_given(s)).quality
    assert q.verdict == "ok"
    return dict(q.evidence)


def test_room_light_whose_removal_matters_did_not_settle_or_outweighs_the_body_is_doubtful(tmp_path):
    e = _evidence(tmp_path)
    phi, beta = e["tilt_amplitude_rad"], e["lateral_amplitude_px"]
    e.update(room_light_fraction=0.2, room_light_settled=True, tilt_amplitude_uncorrected_rad=0.98 * phi,
             lateral_amplitude_uncorrected_px=beta)
    assert strobe_quality(e)["verdict"] == "ok"  # a correction within the tolerance
    e.update(tilt_amplitude_uncorrected_rad=0.8 * phi)
    q = strobe_quality(e)
    assert q["verdict"] == "doubtful" and "moved the result by more than the tolerance" in q["reasons"][0]
    e.update(tilt_amplitude_uncorrected_rad=0.98 * phi, room_light_settled=False)
    q = strobe_quality(e)
    assert q["verdict"] == "doubtful" and "did not settle" in q["reasons"][0]
    e.update(room_light_settled=True, room_light_fraction=0.6)
    q = strobe_quality(e)
    assert q["verdict"] == "doubtful" and "outweighs" in q["reasons"][0]


def test_room_light_fitted_on_a_few_frames_that_does_not_hold_for_the_clip_is_doubtful(tmp_path):
    """The room light is fitted on a few frames; on the robustness suite's strobe-cylinder-26-hard
    the tilt on those frames and on every frame differed by 16 %, and the result was 0.012 rad off
    with verdict ok. A difference over ROOM_LIGHT_HOLDS (10 %) now says doubtful and why."""
    e = _evidence(tmp_path)
    phi, beta = e["tilt_amplitude_rad"], e["lateral_amplitude_px"]
    e.update(room_light_fraction=0.2, room_light_settled=True, tilt_amplitude_uncorrected_rad=0.98 * phi,
             lateral_amplitude_uncorrected_px=beta, room_light_frames_fitted=6,
             tilt_amplitude_fitted_frames_rad=0.95 * phi)
    assert strobe_quality(e)["verdict"] == "ok"  # 5 % apart: as the suite's right results
    e.update(tilt_amplitude_fitted_frames_rad=0.84 * phi)
    q = strobe_quality(e)
    assert q["verdict"] == "doubtful"
    assert any("fitted on 6 frames, does not hold for the whole clip" in r for r in q["reasons"])
    e.update(tilt_amplitude_fitted_frames_rad=None)  # a result of version 1: nothing to compare
    assert strobe_quality(e)["verdict"] == "ok"
