"""Issue 6 acceptance bounds on the seeded synthetic test set (labkit.synth.presets.laser_test_set):
centre error < 1 px, semi-axis relative error < 2 %, rotation error < 2 deg for ellipticity > 0.1,
loop count exact, trochoid a and b within 0.05."""

import math

import pytest

from labkit.synth.presets import laser_test_set
from labkit.vision.laser.analyse import LaserQuality, analyse_laser
from labkit.vision.shared.curves import rotation_error_deg

NAMES = [name for name, _ in laser_test_set()]


@pytest.mark.parametrize("name", NAMES)
def test_laser_pattern_within_acceptance_bounds(laser_clips, name):
    path, truth = laser_clips[name]
    result = analyse_laser(str(path))
    got, want = result.pattern, truth["pattern"]
    assert math.dist(got.center_px, want["center_px"]) < 1.0
    if want["type"] in ("circle", "ellipse"):
        assert got.type in ("circle", "ellipse")
        if want["ellipticity"] >= 0.05:
            assert got.type == "ellipse"
        for g, w in zip(got.semi_axes_px, want["semi_axes_px"], strict=True):
            assert abs(g / w - 1) < 0.02
        if want["ellipticity"] > 0.1:
            err = rotation_error_deg(math.radians(got.rotation_deg), math.radians(want["rotation_deg"]),
                                     math.pi)
            assert err < 2.0
        assert got.trochoid is None
    else:
        assert got.type == want["type"]
        assert got.loops == want["loops"]
        assert abs(got.trochoid.a - want["trochoid"]["a"]) < 0.05
        assert abs(got.trochoid.b - want["trochoid"]["b"]) < 0.05
    assert result.frames == truth["frames"]
    assert result.size == truth["size"]


def test_tilt_from_a_simulated_cone(tmp_path):
    """A simulator-style run of tilt angles: a cone of half-angle phi draws a circle of radius
    L tan(2 phi) on the screen (the beam turns by twice the tilt); analysis gives phi back."""
    import numpy as np

    from labkit.synth import positions_from_angles, render_laser, write_clip
    from labkit.synth.presets import laser_preset

    phi, L, S = 0.05, 400.0, 0.6  # rad, mm, mm/px -> radius 400 tan(0.1) / 0.6 = 66.9 px
    t = np.linspace(0, 1 / 6.1, 400)
    pos = positions_from_angles(t, phi * np.cos(2 * np.pi * 6.1 * t), phi * np.sin(2 * np.pi * 6.1 * t), L, S,
                                (160.0, 120.0))
    spec = laser_preset("medium", (320, 240), seed=5)
    path = write_clip(tmp_path / "cone.mp4", render_laser(spec, pos), spec.fps, "mp4v", None)
    result = analyse_laser(str(path), screen_distance_mm=L, mm_per_px=S)
    assert result.pattern.type == "circle"
    assert result.pattern.semi_axes_px[0] == pytest.approx(L * math.tan(2 * phi) / S, rel=0.02)
    assert result.tilt_rad.major == pytest.approx(phi, rel=0.02)
    assert result.tilt_rad.minor == pytest.approx(phi, rel=0.02)


def test_frame_hook_sees_every_analysed_frame(laser_clips):
    path, truth = laser_clips[NAMES[0]]
    seen = []
    from labkit.vision.laser.analyse import LaserQuality

    analyse_laser(str(path), quality=LaserQuality(stride=3),
                  on_frame=lambda i, t, f: seen.append((i, t, f.shape)))
    assert [i for i, _, _ in seen] == list(range(0, truth["frames"], 3))
    assert seen[1][1] == pytest.approx(3 / truth["fps"])
    assert seen[0][2] == (truth["size"][1], truth["size"][0], 3)


def test_long_clip_is_classified_from_its_first_half_and_refined(tmp_path):
    """With >= 4 chunks the first half is classified while the rest decodes; the end only refines."""
    from dataclasses import replace

    from labkit.synth import laser_truth, render_laser, write_clip
    from labkit.synth.presets import laser_pattern, laser_preset

    size = (320, 240)
    spec = replace(laser_preset("hard", size, seed=5), frames=150,
                   pattern=laser_pattern("hypotrochoid", size, loops=5, b=0.45, rotation_deg=12))
    truth = laser_truth(spec)
    path = write_clip(tmp_path / "long.mp4", render_laser(spec), spec.fps, "mp4v", truth)
    result = analyse_laser(str(path))
    got, want = result.pattern, truth["pattern"]
    assert result.quality.evidence["chunks"] >= 4
    assert any(k.endswith("(first part)") for k in result.quality.evidence["candidate_residuals_px"])
    assert got.type == "hypotrochoid" and got.loops == 5
    assert abs(got.trochoid.b - 0.45) < 0.05
    assert math.dist(got.center_px, want["center_px"]) < 1.0


def test_hard_720p_epitrochoid_with_barely_looped_small_loops(tmp_path):
    """Thick haloed lines at 1280x720 with compression specks beside them, and loops that barely
    form (k b = 1.2). Ranked by the points' residual alone, a 7-loop curve with b = 0.85 passed as
    close to this trace as the true 4-loop one (the default analysis reported 7 loops); a curve
    must also be covered by the light. Known limitation, stated here rather than hidden: the
    halo fills these tiny loops, so b reads 0.05-0.07 high on the luma path (colour: 0.04 low),
    just outside the acceptance set's 0.05."""
    from dataclasses import replace

    from labkit.synth import laser_truth, render_laser, write_clip
    from labkit.synth.presets import laser_pattern, laser_preset

    size = (1280, 720)
    spec = replace(laser_preset("hard", size, seed=42), frames=90,
                   pattern=laser_pattern("epitrochoid", size, loops=4, b=0.3, rotation_deg=20))
    truth = laser_truth(spec)
    path = write_clip(tmp_path / "epi4-hard-720p.mp4", render_laser(spec), spec.fps, "mp4v", truth)
    for stride in (1, 2):
        got = analyse_laser(str(path), quality=LaserQuality(stride=stride)).pattern
        assert got.type == "epitrochoid" and got.loops == 4
        assert math.dist(got.center_px, truth["pattern"]["center_px"]) < 1.0
        assert abs(got.trochoid.b - 0.3) < 0.1


def test_centre_of_a_fast_drifting_long_clip_is_reported_at_the_middle_of_the_recording(tmp_path):
    """20 s drifting at 5 px/s (a 100 px walk) in 12 chunks of 1.7 s (the default). The fit's centre refers to
    the mean time of the trace points, which need not be the middle of the recording: reported
    unmoved it was 0.7 px off here (2 px on a 30 s 720p clip). Moved to the middle along the
    fitted drift, the error is what the trace allows (~0.2 px)."""
    from dataclasses import replace

    from labkit.synth import laser_truth, render_laser, write_clip
    from labkit.synth.presets import laser_pattern, laser_preset

    size = (320, 240)
    spec = replace(laser_preset("hard", size, seed=9), frames=600, drift_px_s=(4.0, -3.0),
                   pattern=laser_pattern("ellipse", size, ellipticity=0.3, rotation_deg=35))
    truth = laser_truth(spec)
    path = write_clip(tmp_path / "drift.mp4", render_laser(spec), spec.fps, "mp4v", truth)
    result = analyse_laser(str(path))
    assert result.quality.evidence["chunks"] == LaserQuality().max_chunks == 12
    assert result.quality.evidence["drift_px_s"] == pytest.approx([4.0, -3.0], abs=0.1)
    assert math.dist(result.pattern.center_px, truth["pattern"]["center_px"]) < 0.35
    for g, w in zip(result.pattern.semi_axes_px, truth["pattern"]["semi_axes_px"], strict=True):
        assert abs(g / w - 1) < 0.02
