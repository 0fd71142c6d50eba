"""issue 26's acceptance on the emulated rig: `labkit run emulated-strobe strobe-sweep --json -` films
four speeds under the locked strobe, each point carries phi, beta and delta with standard errors and
a verdict, every ok point is within 5 % of the model plant's values (stored with the frames), and
`labkit replay` reproduces every point. Also: a strobe whose every status line is flagged gives failed
points that say why; a rig without a camera analyses a recorded clip per step."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
RIG = REPO / "rigs" / "emulated-strobe.toml"


def _run(args: list[str], timeout: float = 240) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "labkit", *args], capture_output=True, text=True,
                          timeout=timeout)


def test_strobe_sweep_on_the_emulated_rig_measures_the_model_and_replays(tmp_path):
    run = _run(["run", "emulated-strobe", "strobe-sweep", "--json", "-", "--sessions", str(tmp_path),
                "--no-progress", "--set", "speeds_rpm=4000:7000:1000"])
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["status"] == "completed"
    points = out["results"]["points"]
    assert [p["target_rpm"] for p in points] == [4000, 5000, 6000, 7000]
    for p in points:
        assert p["verdict"] in ("ok", "doubtful", "failed")
        # the frequencies the analysis used are the strobe's own status lines'
        assert p["strobe_lines"] >= 10 and p["apparent_hz"] == pytest.approx(1.0, abs=1e-3)
        assert p["rotor_hz"] == pytest.approx(p["speed_rpm"] / 60, rel=0.01)
    ok = [p for p in points if p["verdict"] == "ok"]
    assert len(ok) >= 3
    for p in ok:
        for key, model, se in (("phi_rad", "model_phi_rad", "phi_stderr_rad"),
                               ("beta_mm", "model_beta_mm", "beta_stderr_mm"),
                               ("delta_mm", "model_delta_mm", "delta_stderr_mm")):
            assert p[key] == pytest.approx(p[model], rel=0.05), (key, p)
            assert 0 < p[se] < 0.05 * p[key], (se, p)
        assert p["delta_mm"] == pytest.approx(p["beta_mm"] / math.tan(p["phi_rad"]), rel=1e-6)  # Eq. 5.97
    fit = out["results"]["fit"]
    assert fit["model"] == "cone-angle" and len(fit["predicted_rad"]) == len(ok)
    replay = _run(["replay", out["session"]], timeout=180)
    assert replay.returncode == 0, replay.stderr
    assert "results identical" in replay.stdout + replay.stderr


def test_a_strobe_flagging_every_line_gives_failed_points_that_say_why(tmp_path):
    rig = tmp_path / "noisy-strobe.toml"
    rig.write_text(RIG.read_text().replace("role=strobe\"", "role=strobe&faults=noisy:1.0\""))
    run = _run(["run", str(rig), "strobe-sweep", "--json", "-", "--sessions", str(tmp_path / "s"),
                "--no-progress", "--set", "speeds_rpm=5000", "--set", "burst_frames=12"])
    assert run.returncode == 0, run.stderr
    (point,) = json.loads(run.stdout)["results"]["points"]
    assert point["verdict"] == "failed" and point["retaken"] is True and point["phi_rad"] is None
    assert "noisy" in point["strobe_flags"] and "not locked" in point["reasons"][0]


def _clip(path: Path, rotor_hz: float, offset_hz: float, phi: float, delta_px: float) -> None:
    from labkit.footage import Body, Camera, Lamp, StrobeShot, Swing, render_strobe, write_footage

    shot = StrobeShot(Body("cylinder", 75.0, 37.5), Swing(phi, delta_px, rotor_hz, 0.3),
                      Lamp(rotor_hz - offset_hz, 0.0, 20e-6),
                      Camera((320, 240), 30.0, 0.02, 0.0, read_noise=0.004, psf_core_px=1.0),
                      (160.0, 120.0), frames=40, seed=7)
    write_footage(path, render_strobe(shot), 30.0, {"kind": "strobe", "note": "test clip"})


def test_without_a_camera_a_recorded_clip_per_step_is_analysed(tmp_path):
    text = RIG.read_text()
    start = text.index("[devices.camera]")
    rig = tmp_path / "no-camera.toml"
    rig.write_text(text[:start] + text[text.index("[bodies.rotator]"):])
    clips = tmp_path / "clips"
    clips.mkdir()
    phis = {0: 0.15, 1: 0.10}
    for step, rpm in enumerate((5000, 6000)):
        _clip(clips / f"step-{step}.avi", rpm / 60.0, 1.0, phis[step], 13.0)
    run = _run(["run", str(rig), "strobe-sweep", "--json", "-", "--sessions", str(tmp_path / "s"),
                "--no-progress", "--set", "speeds_rpm=5000,6000", "--set", f"clips={clips}",
                "--set", "mm_per_px=0.2", "--set", "exposure_s=0.02"])
    assert run.returncode == 0, run.stderr
    points = json.loads(run.stdout)["results"]["points"]
    assert [Path(p["clip"]).name for p in points] == ["step-0.avi", "step-1.avi"]
    for p in points:
        assert p["verdict"] == "ok", p["reasons"]
        assert p["phi_rad"] == pytest.approx(phis[p["step"]], rel=0.05)
        assert p["delta_mm"] == pytest.approx(13.0 * 0.2, rel=0.05)
        assert p["model_phi_rad"] is None and p["frames"] == 0  # no emulated camera: no model values


def test_without_a_camera_or_clips_the_plan_is_refused_before_anything_opens(tmp_path):
    text = RIG.read_text()
    rig = tmp_path / "no-camera.toml"
    rig.write_text(text[:text.index("[devices.camera]")] + text[text.index("[bodies.rotator]"):])
    run = _run(["run", str(rig), "strobe-sweep", "--sessions", str(tmp_path / "s"), "--no-progress"])
    assert run.returncode != 0
    assert "clips" in run.stderr and "no camera" in run.stderr
    assert not (tmp_path / "s").exists() or not any((tmp_path / "s").iterdir())


def test_the_hints_draw_phi_beta_and_delta_and_survive_the_start_document():
    from labkit.hints import Hints
    from labkit.protocols import PROTOCOLS
    from labkit.stream.blueprints import figure_of, run_blueprint, view_kinds

    hints = PROTOCOLS["strobe-sweep"].hints
    assert Hints.from_json(json.loads(json.dumps(hints.to_json(), allow_nan=False))) == hints
    assert (hints.x, hints.y) == ("speed_rpm", "phi_deg")
    assert [s.y for s in hints.also] == ["beta_mm", "delta_mm"]
    assert {f.y for f in hints.fits_for_report()} == {"phi_rad", "beta_mm", "delta_mm"}
    origins = [origin for _, origin in view_kinds(run_blueprint(figure_of(hints), ["rotor"], []))]
    assert "/eq5_97/also/beta_mm" in origins and "/eq5_97/also/delta_mm" in origins


def test_shrink_crops_the_strobe_fixture_keeping_its_scale_and_refuses_to_guess_a_new_one(tmp_path):
    session = REPO / "recordings" / "sessions" / "strobe-sweep-clean"
    done = _run(["shrink", str(session), str(tmp_path / "cropped"), "--crop", "40,0,240,240"], timeout=180)
    assert done.returncode == 0, done.stderr
    assert json.loads((tmp_path / "cropped" / "run.json").read_text())["params"]["mm_per_px"] == 0.0
    for p in json.loads((tmp_path / "cropped" / "results.json").read_text())["points"]:
        assert p["beta_mm"] == pytest.approx(p["model_beta_mm"], rel=0.05)  # mm per pixel as recorded
    scaled = _run(["shrink", str(session), str(tmp_path / "scaled"), "--scale", "0.5"], timeout=60)
    assert scaled.returncode != 0 and "mm_per_px" in scaled.stderr and not (tmp_path / "scaled").exists()


def test_a_camera_no_strobe_lights_films_dark_frames_and_the_point_fails_saying_so(tmp_path):
    rig = tmp_path / "dark.toml"
    rig.write_text(RIG.read_text().replace("&strobe=strobe&", "&strobe=lamp_elsewhere&"))
    run = _run(["run", str(rig), "strobe-sweep", "--json", "-", "--sessions", str(tmp_path / "s"),
                "--no-progress", "--set", "speeds_rpm=5000", "--set", "burst_frames=12"])
    assert run.returncode == 0, run.stderr
    (point,) = json.loads(run.stdout)["results"]["points"]
    assert point["verdict"] == "failed" and point["retaken"] is True and point["phi_rad"] is None
    assert point["strobe_flags"] == [] and "no body found" in point["reasons"][0]
    assert point["reasons"][1] == "12 of 12 frames lit by no flash (the emulated camera's strobe was dark)"
