"""Seeded synthetic footage for the vision tests, rendered once per session."""

from __future__ import annotations

import pytest

from labkit.synth import laser_truth, render_laser, render_strobe, strobe_truth, write_clip
from labkit.synth.presets import laser_test_set, strobe_preset


@pytest.fixture(scope="session")
def laser_clips(tmp_path_factory):
    """{name: (path, truth)} for the acceptance set (circles, ellipses, trochoids 2-7 loops,
    easy/medium/hard, 320x240 to 1280x720)."""
    folder = tmp_path_factory.mktemp("laser")
    clips = {}
    for name, spec in laser_test_set():
        truth = laser_truth(spec)
        path = write_clip(folder / f"{name}.mp4", render_laser(spec), spec.fps, "mp4v", truth)
        clips[name] = (path, truth)
    return clips


@pytest.fixture(scope="session")
def strobe_clips(tmp_path_factory):
    """{level: (path, truth, spec)} stroboscope clips; hard is a bright body, MJPG, rolling shutter."""
    folder = tmp_path_factory.mktemp("strobe")
    clips = {}
    for i, level in enumerate(("easy", "medium", "hard")):
        spec = strobe_preset(level, seed=20 + i)
        ext, codec = (".avi", "MJPG") if level == "hard" else (".mp4", "mp4v")
        path = write_clip(folder / f"strobe-{level}{ext}", render_strobe(spec), spec.strobe_hz, codec,
                          strobe_truth(spec))
        clips[level] = (path, strobe_truth(spec), spec)
    return clips
