"""The typed results of the two analyses (ADR 0034): attributes for the JSON's top-level keys and
typed parts for its nested objects, ``to_json()`` giving the commands' JSON with its key order,
optional keys absent rather than null, and no dict face."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.vision import LaserResult, StrobeResult, analyse_laser
from labkit.vision.laser.result import LaserPattern
from labkit.vision.shared.result import RecordedSpeeds, Trochoid
from labkit.vision.shared.verdict import QualityReport, Verdict
from labkit.vision.strobe.phase import PhaseModel
from labkit.vision.strobe.result import BodyAxis, InMillimetres, PerFrame, PointPattern, Uncertainty

PHOTO = Path(__file__).resolve().parents[2] / "recordings" / "videos" / "laser-hypotrochoid3-photo.jpg"
STROBE_KEYS = ["source", "frames", "fps", "apparent_hz", "tilt_amplitude_rad", "lateral_amplitude_px",
               "rc_offset_px", "uncertainty", "room_light", "phase_per_frame", "per_frame", "point_pattern",
               "rc_offset_direction", "phase_source", "phase_model", "body", "quality"]


def _strobe(**extra) -> StrobeResult:
    values = {k: None for k in STROBE_KEYS} | {
        "quality": QualityReport.of(Verdict("doubtful", ["r"]), {"point": "tip"}),
        "uncertainty": Uncertainty(0.001, 0.02, None, "1-sigma"),
        "per_frame": PerFrame([0, 1], [0.1, -0.1], [2.0, -2.0]),
        "point_pattern": PointPattern(type="none", reason="only 3 frames with a body"),
        "phase_model": PhaseModel("signal", 0.25, 30.0, 7.5),
        "body": BodyAxis(90.0, 2, 40.0)}
    return StrobeResult(**values | extra)


def test_a_strobe_result_writes_optional_keys_only_when_it_has_them_and_in_the_commands_order():
    plain = _strobe()
    written = plain.to_json()
    assert list(written) == STROBE_KEYS  # room_light and rc_offset_px stay, as null
    assert written["point_pattern"] == {"type": "none", "reason": "only 3 frames with a body"}
    assert written["quality"] == {"verdict": "doubtful", "reasons": ["r"], "point": "tip"}  # no checks
    assert list(written["phase_model"])[-1] == "blur_factor"
    full = _strobe(rolling_shutter=None, in_mm=InMillimetres(1.5, None),
                   uncertainty=Uncertainty(0.001, 0.02, None, "1-sigma", InMillimetres(0.002, None)),
                   speeds=RecordedSpeeds(14400.0, None))
    written = full.to_json()
    assert list(written) == [*STROBE_KEYS, "lateral_amplitude_mm", "rc_offset_mm", "rotor_speed_rpm",
                             "spin_rad_s"]
    assert written["rc_offset_mm"] is None and written["spin_rad_s"] is None
    assert list(written["uncertainty"])[-2:] == ["lateral_amplitude_mm", "rc_offset_mm"]
    assert (full.verdict, full.reasons) == ("doubtful", ["r"])
    assert json.loads(json.dumps(written)) == written  # JSON values only, no typed part left


def test_results_have_no_dict_face_and_their_parts_are_frozen():
    r = _strobe()
    with pytest.raises(TypeError):
        r["quality"]  # type: ignore[index]
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.fps = 30.0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.quality.verdict = "ok"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.body.symmetry = 4  # type: ignore[misc]


def test_a_quality_object_reads_back_with_its_verdict_first_and_the_evidence_in_order():
    quality = {"verdict": "failed", "reasons": ["a", "b"], "checks": {"residual": "failed"},
               "z": 1, "a": None}
    report = QualityReport.from_json(quality)
    assert (report.verdict, report.reasons, report.checks) == ("failed", ("a", "b"), {"residual": "failed"})
    assert list(report.evidence) == ["z", "a"] and report.to_json() == quality
    assert list(report.to_json()) == list(quality)
    with pytest.raises(ValueError, match="starts with its verdict"):
        QualityReport.from_json({"z": 1, "verdict": "ok", "reasons": []})


def test_a_laser_pattern_writes_every_parameter_and_its_reason_only_when_it_has_none():
    none = LaserPattern(type="none", reason="no light above the background noise")
    assert list(none.to_json()) == ["type", "reason", "center_px", "semi_axes_px", "rotation_deg",
                                    "ellipticity", "loops", "symmetry", "trochoid", "rms_residual_px"]
    assert not none.found
    assert all(v is None for k, v in none.to_json().items() if k not in ("type", "reason"))
    troch = LaserPattern(type="hypotrochoid", center_px=[1.0, 2.0], semi_axes_px=[3.0, 1.0],
                         rotation_deg=10.0, loops=3, symmetry=3, trochoid=Trochoid(-1 / 3, 0.5, 2.0, 10.0),
                         rms_residual_px=0.1)
    written = troch.to_json()
    assert "reason" not in written and written["trochoid"] == {"a": -1 / 3, "b": 0.5, "scale_px": 2.0,
                                                                "rotation_deg": 10.0}
    assert LaserPattern.from_json(written) == troch


def test_the_laser_command_writes_the_results_json_and_the_speeds_it_was_given(tmp_path, capsys):
    result = analyse_laser(str(PHOTO))
    assert isinstance(result, LaserResult) and result.found_pattern
    assert result.verdict == result.quality.verdict and result.pattern.type == "hypotrochoid"
    assert isinstance(result.pattern.trochoid, Trochoid) and result.pattern.loops == 3
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
    assert LaserPattern.from_json(written["pattern"]) == result.pattern
    assert QualityReport.from_json(written["quality"]).checks == result.quality.checks
