"""The luma fast path of frame reading: the decoder's own Y plane instead of converted BGR frames.

Independent reference: BT.601 luma of the converted frame (cv2.cvtColor BGR2GRAY), in studio range
(16-235) for MPEG-4 part 2 and full range (0-255) for motion JPEG.
"""

import json
import math
from dataclasses import replace

import cv2
import numpy as np
import pytest

from labkit.synth import laser_truth, render_laser, write_clip
from labkit.synth.presets import laser_pattern, laser_preset
from labkit.vision.laser.analyse import LaserQuality, analyse_laser
from labkit.vision.shared.frames import open_frames


def clip(folder, codec, ext, level="medium", frames=6, size=(320, 240), **pattern):
    spec = replace(laser_preset(level, size, seed=3), frames=frames)
    if pattern:
        spec = replace(spec, pattern=laser_pattern("ellipse", size, **pattern))
    truth = laser_truth(spec)
    return write_clip(folder / f"clip-{codec}{ext}", render_laser(spec), spec.fps, codec, truth), truth


@pytest.mark.parametrize("codec,ext,levels",
                         [("mp4v", ".mp4", (16.0, 235.0)), ("MJPG", ".avi", (0.0, 255.0))])
def test_luma_plane_is_the_bt601_luma_of_the_converted_frame(tmp_path, codec, ext, levels):
    path, _ = clip(tmp_path, codec, ext)
    bgr = [f for _, f in open_frames(path).frames()]
    source = open_frames(path)
    planes = [f for _, f in source.frames(luma=True)]
    assert source.levels == levels
    assert len(planes) == len(bgr) == source.frames_read
    lo, hi = levels
    for plane, frame in zip(planes, bgr, strict=True):
        assert plane.shape == frame.shape[:2] and plane.dtype == np.uint8
        expected = lo + cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY).astype(float) * (hi - lo) / 255
        assert np.mean(np.abs(plane - expected)) < 2.0  # rounding of the YUV -> BGR conversion


def test_luma_falls_back_to_bgr_without_a_planar_luma(tmp_path):
    path, _ = clip(tmp_path, "FFV1", ".mkv", frames=3)
    source = open_frames(path)
    frames = [f for _, f in source.frames(luma=True, prefetch=2)]
    assert len(frames) == 3 and all(f.ndim == 3 for f in frames)
    assert source.levels == (0.0, 255.0)


def test_luma_stride_and_prefetch_give_the_same_frames(tmp_path):
    path, _ = clip(tmp_path, "mp4v", ".mp4", frames=9)
    plain = [(i, f.copy()) for i, f in open_frames(path).frames(stride=3, luma=True)]
    ahead = list(open_frames(path).frames(stride=3, prefetch=2, luma=True))
    assert [i for i, _ in plain] == [i for i, _ in ahead] == [0, 3, 6]
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(plain, ahead, strict=True))


@pytest.mark.parametrize("codec,ext", [("mp4v", ".mp4"), ("MJPG", ".avi")])
def test_luma_and_colour_analyses_both_meet_the_acceptance_bounds(tmp_path, codec, ext):
    path, truth = clip(tmp_path, codec, ext, level="hard", frames=40, size=(640, 480),
                       ellipticity=0.4, rotation_deg=62)
    t = truth["pattern"]
    for luma in (True, False):
        p = analyse_laser(str(path), quality=LaserQuality(luma=luma)).pattern
        assert p.type == "ellipse"
        assert math.dist(p.center_px, t["center_px"]) < 1.0
        for got, want in zip(p.semi_axes_px, t["semi_axes_px"], strict=True):
            assert abs(got / want - 1) < 0.02
        assert abs((p.rotation_deg - t["rotation_deg"] + 90) % 180 - 90) < 2.0


def test_cli_frame_path_options_are_recorded(capsys, tmp_path):
    from labkit.cli import main

    path, truth = clip(tmp_path, "mp4v", ".mp4", frames=12, ellipticity=0.3)
    for argv, luma, frame_path in (([], None, "luma"), (["--luma"], True, "luma"),
                                   (["--colour-frames"], False, "colour")):
        assert main(["analyse", "laser", str(path), "--json", "-", *argv]) == 0
        out = capsys.readouterr().out
        result = json.loads(out[out.index("{"):])
        assert result["quality"]["settings"]["luma"] is luma
        assert result["quality"]["settings"]["max_chunks"] == LaserQuality().max_chunks  # CLI default
        assert result["quality"]["frame_path"] == frame_path
        assert math.dist(result["pattern"]["center_px"], truth["pattern"]["center_px"]) < 1.0


@pytest.mark.parametrize("choose", [True, False])
@pytest.mark.parametrize("frames,stride,prefetch", [(40, 3, 0), (60, 1, 2), (5, 2, 2)])
def test_automatic_choice_yields_exactly_the_forced_paths_frames(tmp_path, choose, frames, stride, prefetch):
    """The luma plane is decoded while the chooser judges the first frames; whatever it decides, the
    frames must be those of the forced path: luma planes when it says yes, and BGR frames (the
    probe's reader carrying on after its head frames) when it says no. Clips shorter and longer
    than the probe and the planes held back meanwhile."""
    path, _ = clip(tmp_path, "mp4v", ".mp4", frames=frames)
    forced = [(i, f.copy()) for i, f in open_frames(path).frames(stride=stride, luma=choose)]
    seen: list[int] = []

    def chooser(head):
        seen.append(len(head))
        assert all(f.ndim == 3 for f in head)  # the chooser always judges colour frames
        return choose

    source = open_frames(path)
    auto = [(i, f.copy()) for i, f in source.frames(stride=stride, prefetch=prefetch, luma=True,
                                                    choose_luma=chooser, probe=8)]
    assert seen == [min(8, frames)] and source.luma_chosen is choose
    assert [i for i, _ in auto] == [i for i, _ in forced] == list(range(0, frames, stride))
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(auto, forced, strict=True))
    assert source.frames_read == frames
    assert source.levels == ((16.0, 235.0) if choose else (0.0, 255.0))


def test_automatic_choice_is_not_asked_without_a_planar_luma(tmp_path):
    path, _ = clip(tmp_path, "FFV1", ".mkv", frames=10)
    asked = []
    source = open_frames(path)
    frames = list(source.frames(luma=True, prefetch=2, choose_luma=lambda head: asked.append(1) or True))
    assert len(frames) == 10 and all(f.ndim == 3 for _, f in frames)
    assert asked == [] and source.luma_chosen is None


class PlaneFirstChooser:
    """A chooser that judges the luma planes first (like the laser analysis's probe)."""

    def __init__(self, ample: bool, choose: bool) -> None:
        self.ample, self.choose = ample, choose
        self.planes_seen: list[int] = []
        self.colour_seen: list[int] = []

    def luma_is_ample(self, planes):
        assert all(p.ndim == 2 for p in planes)  # the decoder's own planes, no colour decoded
        self.planes_seen.append(len(planes))
        return self.ample

    def __call__(self, head):
        assert all(f.ndim == 3 for f in head)
        self.colour_seen.append(len(head))
        return self.choose


@pytest.mark.parametrize("ample,choose", [(True, False), (False, True), (False, False)])
@pytest.mark.parametrize("frames,stride", [(40, 1), (40, 3), (5, 1)])
def test_planes_judged_first_decide_alone_when_ample(tmp_path, ample, choose, frames, stride):
    """Ample planes choose luma without any colour judgement; otherwise the colour frames are
    judged as before. Either way the frames are exactly the forced path's."""
    path, _ = clip(tmp_path, "mp4v", ".mp4", frames=frames)
    luma = ample or choose
    forced = [(i, f.copy()) for i, f in open_frames(path).frames(stride=stride, luma=luma)]
    chooser = PlaneFirstChooser(ample, choose)
    source = open_frames(path)
    auto = [(i, f.copy()) for i, f in source.frames(stride=stride, prefetch=2, luma=True,
                                                    choose_luma=chooser, probe=8)]
    assert chooser.planes_seen == [min(8, len(range(0, frames, stride)))]
    assert chooser.colour_seen == ([] if ample else [min(8, frames)])
    assert source.luma_chosen is luma
    assert [i for i, _ in auto] == [i for i, _ in forced] == list(range(0, frames, stride))
    assert all(np.array_equal(a, b) for (_, a), (_, b) in zip(auto, forced, strict=True))
    assert source.frames_read == frames
