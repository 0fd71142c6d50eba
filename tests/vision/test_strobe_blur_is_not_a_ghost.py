"""A body that hardly moves, filmed with lens blur and no room light at all, has no ambient ghost:
the blurred edge of the part it covers in every frame darkens the clip's static light as a ghost
would, and used to be measured as one (1-10 % of the contrast), which sent the tilt through the
static-light correction 19 % off (the twin's strobe clips; labkit.vision.strobe.analyse.ghost_fraction)."""

from __future__ import annotations

import math

import pytest

from labkit.footage import (
    Body,
    Camera,
    Lamp,
    Lighting,
    StrobeShot,
    Swing,
    render_strobe,
    strobe_truth,
    write_footage,
)
from labkit.vision.strobe.analyse import GHOST_FLOOR, analyse_strobe

FPS = 30.0
PHI = 0.10146


@pytest.mark.parametrize("mm_per_px", [0.17, 0.25])
def test_blurred_body_without_room_light_is_measured_as_ghost_free(mm_per_px, tmp_path):
    rotor_hz = 7 * FPS + 0.16 * FPS
    delta_px = 2.659 / mm_per_px  # the model floator's RC offset: a lateral swing of 1-2 px
    body = Body("cylinder", 15.0 / mm_per_px, 7.5 / mm_per_px)
    shot = StrobeShot(body, Swing(PHI, delta_px, rotor_hz, 1.0), Lamp(FPS, 0.2 / FPS, 20e-6),
                      Camera((640, 480), FPS, 0.5 / FPS, 0.0, read_noise=0.01, psf_core_px=1.0),
                      (320.0, 240.0), lighting=Lighting(level=0.0), ambient=0.0, frames=60, seed=3)
    path = write_footage(tmp_path / "still.mp4", render_strobe(shot), FPS, strobe_truth(shot))
    result = analyse_strobe(str(path), rotor_hz=rotor_hz, strobe_hz=FPS)
    quality = result.quality
    assert quality.evidence["ghost_fraction"] <= GHOST_FLOOR, quality
    assert quality.evidence["axis_method"] == "linear moments"
    assert abs(result.tilt_amplitude_rad - PHI) <= max(0.05 * PHI, 0.005), result.tilt_amplitude_rad
    assert quality.verdict == "ok", quality.reasons
    assert math.isfinite(result.lateral_amplitude_px)
