"""Room light's ghost of the revolution on footage from the independent renderer (labkit.footage,
issue 11; renderer v4 sends the ghost through the lens as it does the flashes): the analysis takes
the ghost out in linear light (labkit.vision.strobe.room_light) and says how much room light it found."""

from __future__ import annotations

import pytest

from labkit.footage.output import write_footage
from labkit.footage.strobe_scene import render_strobe, strobe_truth
from labkit.footage.suite import suite_cases
from labkit.footage.suite_build import build_shot
from labkit.footage.suite_eval import analysis_inputs, score_strobe
from labkit.vision.strobe.analyse import analyse_strobe

CASE = "strobe-cuboid-23-hard"  # 320x240, a spinning plate, one flash per exposure, room light 0.3


@pytest.fixture(scope="module")
def room_lit(tmp_path_factory):
    (case,) = [c for c in suite_cases(only="strobe", difficulty="hard") if c.name == CASE]
    shot = build_shot(case)
    assert shot.ambient > 0 and shot.camera.halo_fraction > 0  # room light and a lens halo
    truth = strobe_truth(shot)
    path = write_footage(tmp_path_factory.mktemp("room") / "clip.mp4", render_strobe(shot), shot.camera.fps,
                         truth, jpeg_quality=shot.camera.jpeg_quality)
    given = analysis_inputs(truth)  # what a user passes: the rotor and lamp frequencies
    return shot, truth, analyse_strobe(str(path), rotor_hz=given["rotor_hz"], strobe_hz=given["strobe_hz"])


def test_room_light_is_taken_out_within_tolerance(room_lit):
    _, truth, result = room_lit
    failures, errors = score_strobe(result.to_json(), truth)
    assert failures == [], errors
    room = result.room_light
    assert room.settled and result.quality.evidence["axis_method"] == "linear moments, room light taken out"


def test_the_room_light_found_is_the_scenes(room_lit):
    """The renderer adds room light at 0.3 of the lamp's light: 0.23 of all the light."""
    shot, _, result = room_lit
    share = shot.ambient / (1 + shot.ambient)
    assert result.room_light.fraction_of_light == pytest.approx(share, abs=0.06)


def test_without_the_correction_the_swing_comes_out_smaller(room_lit):
    """The ghost does not move, so a body measured with it swings less: the uncorrected tilt is
    further from the truth, on the low side."""
    _, truth, result = room_lit
    phi = truth["tilt_amplitude_rad"]
    uncorrected = result.room_light.tilt_amplitude_uncorrected_rad
    assert uncorrected < phi
    assert abs(result.tilt_amplitude_rad - phi) < abs(uncorrected - phi)
