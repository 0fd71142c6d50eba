"""Automatic choice of the luma fast path: luma only where it keeps the trace's contrast.

Independent reasons for the expectations: BT.601 luma of a pure-red laser is 0.299 of its red
level, so on a warm bright screen (red channel near the top, noise sigma 3) a trace 15 grey levels
above the screen in red sits only ~4.5 levels above it in luma, at or below the detection limit of
8 x noise; the neutral acceptance clips (bright trace on a dim screen) keep most of their contrast.
"""

import math
from dataclasses import replace

import numpy as np
import pytest

from labkit.synth import laser_truth, render_laser, write_clip
from labkit.synth.presets import laser_pattern, laser_preset
from labkit.vision.laser.analyse import LaserQuality, analyse_laser
from labkit.vision.laser.frame_path import AMPLE_LUMA_CNR, PROBE_FRAMES, luma_plane_cnr, measure_frame_path
from labkit.vision.shared.frames import open_frames

SIZE = (640, 480)


def _within_bounds(result: dict, truth: dict) -> bool:
    got, want = result.pattern, truth["pattern"]
    if got.center_px is None or got.type not in ("circle", "ellipse"):
        return False
    axes = all(abs(g / w - 1) < 0.02 for g, w in zip(got.semi_axes_px, want["semi_axes_px"], strict=True))
    return math.dist(got.center_px, want["center_px"]) < 1.0 and axes


@pytest.fixture(scope="module")
def faint_red_on_warm_screen(tmp_path_factory):
    spec = replace(laser_preset("easy", SIZE, seed=7), frames=45, background=190.0, brightness=0.06,
                   noise_sigma=3.0, background_bgr=(0.7, 0.88, 1.0), laser_bgr=(0.0, 0.05, 1.0),
                   pattern=laser_pattern("ellipse", SIZE, ellipticity=0.3))
    truth = laser_truth(spec)
    folder = tmp_path_factory.mktemp("warm")
    path = write_clip(folder / "warm.mp4", render_laser(spec), spec.fps, "mp4v", truth)
    return str(path), truth


def test_auto_keeps_luma_where_it_is_adequate(laser_clips):
    path, truth = laser_clips["03-ellipse-medium-640x480"]
    result = analyse_laser(str(path))
    q = result.quality
    assert q.evidence["frame_path"] == "luma"
    assert q.evidence["settings"]["luma"] is None
    # the decoder's luma planes alone show the trace clearly: colour is not even decoded
    assert q.evidence["cnr_luma"] >= AMPLE_LUMA_CNR and q.evidence["cnr_colour"] is None
    assert _within_bounds(result, truth)


def test_luma_planes_and_converted_grey_score_alike(laser_clips):
    """The planes' CNR (what the shortcut measures) and the CNR of the BT.601 grey of the converted
    frames (what the full rule measures) are contrast over noise of the same light. Studio-range
    planes span 219 of 255 levels, so their contrast is ~0.86 of the grey's: the shortcut is a
    little stricter than the full rule, never looser (the fallback to colour stays safe)."""
    path, _ = laser_clips["03-ellipse-medium-640x480"]
    source = open_frames(path)
    planes = [f.copy() for (_, f), _ in zip(source.frames(luma=True), range(PROBE_FRAMES), strict=False)]
    source = open_frames(path)
    bgr = [f.copy() for (_, f), _ in zip(source.frames(), range(PROBE_FRAMES), strict=False)]
    from_planes = luma_plane_cnr(planes, frame_px=max(source.size))
    from_grey = measure_frame_path(bgr, frame_px=max(source.size)).cnr_luma
    assert 0.8 * from_grey <= from_planes <= from_grey


def test_auto_falls_back_to_colour_for_a_faint_red_trace_on_a_warm_screen(faint_red_on_warm_screen):
    path, truth = faint_red_on_warm_screen
    auto = analyse_laser(path)
    q = auto.quality
    assert q.evidence["frame_path"] == "colour"
    assert q.evidence["cnr_luma"] < 0.5 * q.evidence["cnr_colour"]
    assert _within_bounds(auto, truth)
    forced = analyse_laser(path, quality=LaserQuality(luma=True))
    assert forced.quality.evidence["frame_path"] == "luma"
    assert not _within_bounds(forced, truth)  # what the fallback saves the user from


def test_forcing_colour_skips_the_measurement(faint_red_on_warm_screen):
    path, _ = faint_red_on_warm_screen
    q = analyse_laser(path, quality=LaserQuality(luma=False)).quality
    e = q.evidence
    assert e["frame_path"] == "colour" and e["cnr_luma"] is None and e["cnr_colour"] is None


def test_measurement_on_frames_with_known_contrast():
    """A 1-px-wide vertical line, 40 levels above a flat screen with noise sigma 2 per channel:
    pure blue light keeps 0.114 of its level in luma, white light all of it."""
    rng = np.random.default_rng(1)
    frames = []
    for colour in ((1.0, 0.0, 0.0), (1.0, 1.0, 1.0)):
        img = np.full((240, 320, 3), 60.0, np.float32)
        img[:, 160:163] += 40.0 * np.array(colour, np.float32)
        stack = [np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8) for _ in range(4)]
        frames.append(measure_frame_path(stack))
    blue, white = frames
    assert not blue.luma and blue.cnr_luma < 0.3 * blue.cnr_colour
    assert white.luma and white.cnr_luma >= 0.6 * white.cnr_colour


def test_cli_reports_the_fallback(faint_red_on_warm_screen, capsys):
    from labkit.cli import main

    path, _ = faint_red_on_warm_screen
    main(["analyse", "laser", path])
    out = capsys.readouterr().out
    assert "frames: colour" in out and "in luma vs" in out
