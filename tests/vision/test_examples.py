"""The committed example clips (recordings/videos) through the CLI: results against their ground
truth, and the JSON layout the issue specifies."""

import json
import math
from pathlib import Path

import pytest

from labkit.cli import main

VIDEOS = Path(__file__).resolve().parents[2] / "recordings" / "videos"
LASER_KEYS = {"source", "frames", "fps", "size", "pattern", "tilt_rad", "quality",
              "rotor_speed_rpm", "spin_rad_s"}  # the last two from the CLI (--speed-rpm, --spin-rad-s)
PATTERN_KEYS = {"type", "center_px", "semi_axes_px", "rotation_deg", "ellipticity", "loops", "symmetry",
                "trochoid", "rms_residual_px"}
STROBE_KEYS = {"source", "frames", "apparent_hz", "tilt_amplitude_rad", "lateral_amplitude_px",
               "rc_offset_px", "phase_per_frame", "point_pattern"}


def analyse(capsys, tmp_path, *argv):
    out = tmp_path / "out.json"
    rc = main(["analyse", *argv, "--json", str(out)])
    text = capsys.readouterr()
    assert "Traceback" not in text.out + text.err
    return rc, json.loads(out.read_text()), text.out


@pytest.mark.parametrize("name", ["laser-ellipse-medium.mp4", "laser-hypotrochoid3-photo.jpg",
                                  "laser-epitrochoid4-hard.mp4"])
def test_laser_examples(capsys, tmp_path, name):
    truth = json.loads((VIDEOS / name).with_suffix(".truth.json").read_text())["pattern"]
    L, S = 500.0, 0.4
    rc, r, out = analyse(capsys, tmp_path, "laser", str(VIDEOS / name), "--screen-distance-mm", str(L),
                         "--mm-per-px", str(S))
    assert rc == 0
    assert set(r) == LASER_KEYS and set(r["pattern"]) == PATTERN_KEYS
    assert set(r["tilt_rad"]) == {"major", "minor"}
    p = r["pattern"]
    assert p["type"] == truth["type"] and p["loops"] == truth["loops"]
    assert math.dist(p["center_px"], truth["center_px"]) < 1.0
    assert r["quality"]["verdict"] == "ok" and r["quality"]["reasons"] == []
    assert "quality: result ok" in out
    if truth["trochoid"]:
        assert set(p["trochoid"]) == {"a", "b", "scale_px", "rotation_deg"}
        assert p["symmetry"] == round(1 / abs(truth["trochoid"]["a"]))
        assert abs(p["trochoid"]["b"] - truth["trochoid"]["b"]) < 0.05
        assert p["ellipticity"] is None
    else:
        assert p["trochoid"] is None
        assert p["semi_axes_px"] == pytest.approx(truth["semi_axes_px"], rel=0.02)
        assert p["ellipticity"] == pytest.approx(truth["ellipticity"], abs=0.02)
    # the beam turns by twice the tilt: tan(2 tilt) = r S / L
    assert math.tan(2 * r["tilt_rad"]["major"]) == pytest.approx(p["semi_axes_px"][0] * S / L)
    assert p["type"] in out  # the human summary names the pattern


def test_strobe_example(capsys, tmp_path):
    truth = json.loads((VIDEOS / "strobe-medium.truth.json").read_text())
    spec = truth["spec"]
    rc, r, _ = analyse(capsys, tmp_path, "strobe", str(VIDEOS / "strobe-medium.mp4"), "--rotor-hz",
                       str(spec["rotor_hz"]), "--strobe-hz", str(spec["strobe_hz"]))
    assert rc == 0
    assert STROBE_KEYS <= set(r)
    assert len(r["phase_per_frame"]) == r["frames"] == truth["frames"]
    assert r["tilt_amplitude_rad"] == pytest.approx(truth["tilt_amplitude_rad"], rel=0.05)
    # Eq. 5.97: delta = beta / tan(phi)
    assert r["rc_offset_px"] == pytest.approx(r["lateral_amplitude_px"] / math.tan(r["tilt_amplitude_rad"]))
    assert r["rc_offset_px"] == pytest.approx(truth["rc_offset_px"], rel=0.05)
    assert {"type", "center_px"} <= set(r["point_pattern"])


def test_synth_cli_writes_clip_and_truth(capsys, tmp_path):
    out = tmp_path / "c.avi"
    assert main(["synth", "laser", str(out), "--pattern", "hypotrochoid", "--loops", "4", "--size", "160x120",
                 "--frames", "5", "--codec", "MJPG", "--level", "easy"]) == 0
    truth = json.loads((tmp_path / "c.truth.json").read_text())
    assert truth["pattern"]["loops"] == 4 and truth["pattern"]["trochoid"]["a"] == pytest.approx(-0.25)
    import cv2

    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 5
    assert main(["synth", "laser", str(tmp_path / "d.mp4"), "--pattern", "hypotrochoid", "--loops", "2"]) == 2
    assert "3-7" in capsys.readouterr().err


def test_synth_from_simulator_angles(capsys, tmp_path):
    import numpy as np

    t = np.linspace(0, 0.2, 50)
    csv = tmp_path / "run.csv"
    np.savetxt(csv, np.column_stack([t, 0.03 * np.cos(31.4 * t), 0.02 * np.sin(31.4 * t)]), delimiter=",",
               header="t_s,tilt_x_rad,tilt_y_rad")
    assert main(["synth", "laser", str(tmp_path / "sim.png"), "--angles", str(csv), "--size", "320x240",
                 "--screen-distance-mm", "300", "--mm-per-px", "0.5", "--level", "easy", "--frames", "10",
                 "--exposure-ms", "40"]) == 0
    rc, r, _ = analyse(capsys, tmp_path, "laser", str(tmp_path / "sim.png"), "--screen-distance-mm", "300",
                       "--mm-per-px", "0.5")
    assert rc == 0 and r["pattern"]["type"] == "ellipse"
    assert r["tilt_rad"]["major"] == pytest.approx(0.03, rel=0.03)
    assert r["tilt_rad"]["minor"] == pytest.approx(0.02, rel=0.03)
    bad = tmp_path / "bad.csv"
    bad.write_text("1,2\n")
    assert main(["synth", "laser", str(tmp_path / "x.png"), "--angles", str(bad)]) == 2
