"""User story 4 step 3 end to end: one clip per rotor speed, analysed with ``--speed-rpm``, then
``labkit fit *.json --model cone-angle`` recovers the torques that drew the cones (Eq. 5.24).

The clips are drawn from the closed form of :mod:`labkit.model` (known tau_C, tau_S, I): a cone
of half-angle phi turns the reflected beam by 2 phi, so the spot runs round a circle of radius
L tan(2 phi) on a screen square to the cone's axis.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from labkit.cli import main
from labkit.model.cone import cone_angle
from labkit.units import rpm_to_rad_s

I_KG_M2, TAU_C, TAU_S = 1e-7, 8e-3, 1e-2  # N m: angles 0.10 rad at 9000 rpm down to 0.019 at 20000
L_MM, S_MM_PX = 400.0, 0.8
SPEEDS_RPM = (9000, 11000, 13500, 16500, 20000)


def render_cone_clip(path: Path, phi: float, seed: int) -> Path:
    """A 320x240, 30-frame easy laser clip of a cone of half-angle ``phi`` (rad)."""
    from labkit.synth import positions_from_angles, render_laser, write_clip
    from labkit.synth.presets import laser_preset

    cycle_hz = 7.3
    t = np.linspace(0.0, 1.0 / cycle_hz, 400)
    turn = 2 * np.pi * cycle_hz * t
    # face-normal tilts whose reflected beam meets the screen on the circle of radius L tan(2 phi)
    tilt_x = 0.5 * np.arctan(np.tan(2 * phi) * np.cos(turn))
    tilt_y = 0.5 * np.arctan(np.tan(2 * phi) * np.sin(turn))
    position = positions_from_angles(t, tilt_x, tilt_y, L_MM, S_MM_PX, (160.37, 119.79))
    spec = replace(laser_preset("easy", (320, 240), seed=seed), frames=30)
    return write_clip(path, render_laser(spec, position), spec.fps, "mp4v", None)


def analyse(clip: Path, out: Path, *extra: str) -> int:
    return main(["analyse", "laser", str(clip), "--screen-distance-mm", str(L_MM),
                 "--mm-per-px", str(S_MM_PX), "--json", str(out), *extra])


@pytest.fixture(scope="module")
def cone_clips(tmp_path_factory) -> Path:
    """A folder with one clip per rotor speed and its analysis JSON (``cone-NNNNNrpm.json``)."""
    folder = tmp_path_factory.mktemp("cones")
    for i, rpm in enumerate(SPEEDS_RPM):
        phi = float(cone_angle(TAU_C, TAU_S, I_KG_M2, rpm_to_rad_s(rpm)))
        clip = render_cone_clip(folder / f"cone-{rpm:05d}rpm.mp4", phi, seed=40 + i)
        assert analyse(clip, clip.with_suffix(".json"), "--speed-rpm", str(rpm)) == 0
    return folder


def fit_json(args: list[str], capsys) -> dict:
    assert main(["fit", *args, "--json", "-"]) == 0
    return json.loads(capsys.readouterr().out)


def test_speed_recorded_in_the_laser_json(cone_clips: Path):
    doc = json.loads((cone_clips / "cone-13500rpm.json").read_text())
    assert doc["rotor_speed_rpm"] == 13500.0
    assert doc["spin_rad_s"] is None
    want = float(cone_angle(TAU_C, TAU_S, I_KG_M2, rpm_to_rad_s(13500)))
    assert doc["tilt_rad"]["major"] == pytest.approx(want, rel=0.01)


def test_spin_recorded_and_absent_speed_is_null(cone_clips: Path, tmp_path: Path, capsys):
    clip = cone_clips / "cone-20000rpm.mp4"
    assert analyse(clip, tmp_path / "spin.json", "--speed-rpm", "20000", "--spin-rad-s", "-35.5") == 0
    assert "rotor speed 20000 rpm  floator spin -35.5 rad/s" in capsys.readouterr().out
    doc = json.loads((tmp_path / "spin.json").read_text())
    assert (doc["rotor_speed_rpm"], doc["spin_rad_s"]) == (20000.0, -35.5)
    assert analyse(clip, tmp_path / "plain.json") == 0
    doc = json.loads((tmp_path / "plain.json").read_text())
    assert doc["rotor_speed_rpm"] is None and doc["spin_rad_s"] is None


def test_fit_of_the_clips_recovers_the_cyclic_torque(cone_clips: Path, tmp_path: Path, capsys):
    """tau_C within its 95 % interval and within 1 % with tau_S fixed at its true value."""
    table = tmp_path / "cones.csv"
    doc = fit_json([str(cone_clips / "cone-*.json"), "--model", "cone-angle", "--inertia", str(I_KG_M2),
                    "--fix", f"tau_S={TAU_S}", "--table", str(table)], capsys)
    res = doc["series"]["all"]
    assert res["n"] == len(SPEEDS_RPM)
    assert doc["columns"]["x"] == "speed_rpm" and doc["columns"]["y"] == "cone_angle_rad"
    tau_c = res["params"]["tau_C"]
    assert tau_c["value"] == pytest.approx(TAU_C, rel=0.01)
    assert tau_c["ci95"][0] <= TAU_C <= tau_c["ci95"][1]
    assert res["params"]["tau_S"]["fixed"]
    lines = [ln for ln in table.read_text().splitlines() if not ln.startswith("#")]
    assert lines[0].split(",")[:2] == ["speed_rpm", "cone_angle_rad"]
    assert sorted(float(ln.split(",")[0]) for ln in lines[1:]) == list(SPEEDS_RPM)


def test_fit_of_the_folder_with_both_torques_free(cone_clips: Path, capsys):
    doc = fit_json([str(cone_clips), "--model", "cone-angle", "--inertia", str(I_KG_M2)], capsys)
    p = doc["series"]["all"]["params"]
    assert p["tau_C"]["value"] == pytest.approx(TAU_C, rel=0.02)
    assert p["tau_S"]["value"] == pytest.approx(TAU_S, rel=0.02)


def test_clip_without_speed_stops_the_fit_naming_it(cone_clips: Path, tmp_path: Path, capsys):
    stray = tmp_path / "forgot.json"
    assert analyse(cone_clips / "cone-09000rpm.mp4", stray) == 0
    capsys.readouterr()
    args = [str(p) for p in sorted(cone_clips.glob("*.json"))] + [str(stray)]
    assert main(["fit", *args, "--model", "cone-angle", "--inertia", str(I_KG_M2)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"{stray}:rotor_speed_rpm: no rotor speed recorded" in err and "--speed-rpm RPM" in err


def test_clip_without_scale_stops_the_fit_naming_it(cone_clips: Path, tmp_path: Path, capsys):
    stray = tmp_path / "noscale.json"
    assert main(["analyse", "laser", str(cone_clips / "cone-11000rpm.mp4"), "--speed-rpm", "11000",
                 "--json", str(stray)]) == 0
    capsys.readouterr()
    assert main(["fit", str(cone_clips / "*.json"), str(stray), "--model", "cone-angle"]) == 2
    err = capsys.readouterr().err
    assert f"{stray}:tilt_rad: no tilt: analysed without --screen-distance-mm and --mm-per-px" in err


def test_strobe_records_the_rotor_speed_from_rotor_hz(tmp_path: Path, capsys):
    from labkit.synth import render_strobe, strobe_truth, write_clip
    from labkit.synth.presets import strobe_preset

    spec = strobe_preset("easy", seed=7)
    clip = write_clip(tmp_path / "strobe.mp4", render_strobe(spec), spec.strobe_hz, "mp4v",
                      strobe_truth(spec))
    out = tmp_path / "strobe.json"
    assert main(["analyse", "strobe", str(clip), "--rotor-hz", str(spec.rotor_hz), "--strobe-hz",
                 str(spec.strobe_hz), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["rotor_speed_rpm"] == pytest.approx(60 * spec.rotor_hz)
    assert doc["spin_rad_s"] is None
    assert f"rotor speed {60 * spec.rotor_hz:.6g} rpm" in capsys.readouterr().out

    from labkit.fit.data import load_table

    row = load_table(out)
    assert row.numeric["speed_rpm"].tolist() == [pytest.approx(60 * spec.rotor_hz)]
    assert row.numeric["cone_angle_rad"][0] == doc["tilt_amplitude_rad"]
    assert math.isclose(row.numeric["cone_angle_rad"][0], spec.tilt_amplitude_rad, rel_tol=0.05)

    tach = 60 * spec.rotor_hz * 1.05  # the tachometer's reading wins, with a warning
    assert main(["analyse", "strobe", str(clip), "--rotor-hz", str(spec.rotor_hz), "--strobe-hz",
                 str(spec.strobe_hz), "--speed-rpm", str(tach), "--json", str(out)]) == 0
    assert json.loads(out.read_text())["rotor_speed_rpm"] == pytest.approx(tach)
    assert "differs from 60 x --rotor-hz" in capsys.readouterr().err


def test_strobe_clips_fit_with_speeds_from_rotor_hz(tmp_path: Path, capsys):
    """Side views of the same kind of run: the speed comes from --rotor-hz alone, the angle from
    the strobe's tilt amplitude (within 5 % per clip); the fit recovers tau_C within 2 %."""
    from labkit.synth import render_strobe, write_clip
    from labkit.synth.presets import strobe_preset

    tau_c = 2.4e-2  # N m: 0.30 rad at 9000 rpm down to 0.083 rad at 16500 rpm, visible from the side
    for i, rpm in enumerate((9000, 11000, 13500, 16500)):
        phi = float(cone_angle(tau_c, TAU_S, I_KG_M2, rpm_to_rad_s(rpm)))
        rotor_hz = rpm / 60
        spec = replace(strobe_preset("easy", seed=60 + i), rotor_hz=rotor_hz, strobe_hz=rotor_hz / 10 - 0.3,
                       tilt_amplitude_rad=phi)
        clip = write_clip(tmp_path / f"side-{rpm:05d}rpm.mp4", render_strobe(spec), spec.strobe_hz, "mp4v",
                          None)
        assert main(["analyse", "strobe", str(clip), "--rotor-hz", str(rotor_hz), "--strobe-hz",
                     str(spec.strobe_hz), "--json", str(clip.with_suffix(".json"))]) == 0
    capsys.readouterr()
    doc = fit_json([str(tmp_path), "--model", "cone-angle", "--inertia", str(I_KG_M2),
                    "--fix", f"tau_S={TAU_S}"], capsys)
    assert doc["series"]["all"]["n"] == 4
    assert doc["series"]["all"]["params"]["tau_C"]["value"] == pytest.approx(tau_c, rel=0.02)
