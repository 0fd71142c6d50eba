"""The strobe analysis on footage it was not tuned on (issue 26, item 5): a strobe-lit cylinder drawn
by labkit.testing.strobe_cylinder (its own geometry, light added in linear units, power-law
encoding, MJPEG), small, medium and large for the frame, with and without room light. Tilt and
lateral amplitude must be within the acceptance (5 % or 0.005 rad; 5 % or 0.5 px), the room light
found where there is some and the room-light model not run where there is none.
(docs/explanation/strobe-speed.md has the same clips at 640x480 and 1080p, timed by
``labkit bench vision``.)"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import pytest

from labkit.testing.strobe_cylinder import sized, write_clip
from labkit.vision.strobe.analyse import GHOST_FLOOR, analyse_strobe

sys.path.insert(0, str(Path(__file__).resolve().parent))
from strobe_scenes import lateral_ok, tilt_ok  # noqa: E402  (the acceptance's tolerances)

SIZE = (320, 240)
ROOM = 0.5  # room light over one exposure's flash light: a third of all the light


def _clip(body: str, room: float, seed: int):
    # 2 s at 30 fps, the lamp 1 Hz below the rotor: two apparent cycles
    return replace(sized(body, SIZE, room_light=room), frames=60, strobe_hz=199.0, seed=seed)


@pytest.mark.parametrize("body", ["small", "medium", "large"])
@pytest.mark.parametrize("room", [0.0, ROOM])
def test_amplitudes_within_the_acceptance_for_every_body_size(tmp_path, body, room):
    clip = _clip(body, room, seed=len(body) + int(10 * room))
    path = write_clip(clip, tmp_path / f"{body}.avi")
    r = analyse_strobe(path, rotor_hz=clip.rotor_hz, strobe_hz=clip.strobe_hz)
    truth = clip.truth()
    assert tilt_ok(r.tilt_amplitude_rad, truth["tilt_amplitude_rad"]), (r.tilt_amplitude_rad, truth)
    assert lateral_ok(r.lateral_amplitude_px, truth["lateral_amplitude_px"]), (
        r.lateral_amplitude_px, truth)
    quality = r.quality
    assert quality.verdict != "failed", quality.reasons
    if room:
        assert r.room_light.fraction_of_light == pytest.approx(room / (1 + room), abs=0.06)
        assert quality.evidence["ghost_fraction"] > GHOST_FLOOR
    else:  # the cheap test said no ghost: the room-light model did not run, and says so
        assert r.room_light is None and quality.evidence["ghost_fraction"] <= GHOST_FLOOR
        assert "not run" in quality.evidence["room_light_model"]


def test_the_renderer_draws_what_its_truth_says():
    """The outline's extent and the Eq. 5.97 lateral amplitude the truth reports."""
    import math

    import numpy as np

    from labkit.testing.strobe_cylinder import outline

    clip = sized("large")
    length, width = clip.extent_px()
    pts = outline(clip, 0.0)  # rest axis vertical: length along y
    assert np.ptp(pts[:, 1]) == pytest.approx(length, rel=1e-3)
    assert np.ptp(pts[:, 0]) == pytest.approx(width, rel=1e-3)
    assert 195 <= length <= 215 and 85 <= width <= 95  # "about 200x90 px"
    swung = outline(clip, clip.phi_rad).mean(axis=0) - outline(clip, 0.0).mean(axis=0)
    assert float(np.hypot(*swung)) == pytest.approx(clip.delta_px * math.tan(clip.phi_rad), rel=1e-6)
    assert clip.truth()["lateral_amplitude_px"] == pytest.approx(10.0, abs=0.1)
