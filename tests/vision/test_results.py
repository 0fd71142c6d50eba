"""The typed results of the two analyses (ADR 0034): attributes for the JSON's top-level keys,
``to_json()`` giving the commands' JSON with its key order, optional keys absent rather than
null, and a read-only mapping face equal to the JSON."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.vision import LaserResult, StrobeResult, analyse_laser
from labkit.vision.shared.result import RecordedSpeeds
from labkit.vision.strobe.result import InMillimetres

PHOTO = Path(__file__).resolve().parents[2] / "recordings" / "videos" / "laser-hypotrochoid3-photo.jpg"
STROBE_KEYS = ["source", "frames", "fps", "apparent_hz", "tilt_amplitude_rad", "lateral_amplitude_px",
               "rc_offset_px", "uncertainty", "room_light", "phase_per_frame", "per_frame", "point_pattern",
               "rc_offset_direction", "phase_source", "phase_model", "body", "quality"]


def _strobe(**extra) -> StrobeResult:
    values = {k: None for k in STROBE_KEYS} | {"quality": {"verdict": "doubtful", "reasons": ["r"]}}
    return StrobeResult(**values | extra)


def test_a_strobe_result_writes_optional_keys_only_when_it_has_them_and_in_the_commands_order():
    plain = _strobe()
    assert list(plain.to_json()) == STROBE_KEYS  # room_light and rc_offset_px stay, as null
    full = _strobe(rolling_shutter={"converged": True}, in_mm=InMillimetres(1.5, None),
                   speeds=RecordedSpeeds(14400.0, None), overlay_frame={"bgr": object()})
    assert list(full.to_json()) == [*STROBE_KEYS, "rolling_shutter", "lateral_amplitude_mm", "rc_offset_mm",
                                    "rotor_speed_rpm", "spin_rad_s"]
    assert full.to_json()["rc_offset_mm"] is None and full.to_json()["spin_rad_s"] is None
    assert (full.verdict, full.reasons) == ("doubtful", ["r"])
    assert dict(full) == full.to_json() and full["lateral_amplitude_mm"] == 1.5
    with pytest.raises(KeyError):
        full["overlay_frame"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        full.fps = 30.0  # type: ignore[misc]


def test_the_laser_command_writes_the_results_json_and_the_speeds_it_was_given(tmp_path, capsys):
    result = analyse_laser(str(PHOTO))
    assert isinstance(result, LaserResult) and result.found_pattern
    assert result.verdict == result.quality["verdict"] and result.pattern is result["pattern"]
    out = tmp_path / "r.json"
    assert main(["analyse", "laser", str(PHOTO), "--speed-rpm", "900", "--json", str(out)]) == 0
    written = json.loads(out.read_text())
    mine = json.loads(json.dumps(result.to_json()))
    volatile = {"elapsed_s", "fit_s"}
    assert list(written) == [*mine, "rotor_speed_rpm", "spin_rad_s"]
    assert (written["rotor_speed_rpm"], written["spin_rad_s"]) == (900.0, None)
    for key in mine:
        if key == "quality":
            assert {k: v for k, v in written[key].items() if k not in volatile} == \
                   {k: v for k, v in mine[key].items() if k not in volatile}
        else:
            assert written[key] == mine[key], key
