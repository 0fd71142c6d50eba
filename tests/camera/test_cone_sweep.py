"""issue 25's acceptance on the emulated rig: `labkit run emulated-camera cone-sweep --json -` films
six speeds, each point carries a cone angle and a verdict, the Eq. 5.24 fit recovers the model's
cone angles within 5 % at every ok step, and `labkit replay` reproduces every point."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from labkit.vision.laser.version import LASER_ANALYSIS


def test_cone_sweep_on_the_emulated_camera_rig_fits_the_model_and_replays(tmp_path):
    run = subprocess.run([sys.executable, "-m", "labkit", "run", "emulated-camera", "cone-sweep",
                          "--json", "-", "--sessions", str(tmp_path), "--no-progress",
                          "--set", "burst_frames=20"],
                         capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["status"] == "completed"
    points, fit = out["results"]["points"], out["results"]["fit"]
    assert len(points) >= 6
    assert all(p["cone_angle_rad"] is not None and p["verdict"] in ("ok", "doubtful", "failed")
               for p in points)
    ok = [p for p in points if p["verdict"] == "ok"]
    assert len(ok) >= 5
    for p in ok:
        assert p["cone_angle_rad"] == pytest.approx(p["model_cone_angle_rad"], rel=0.05), p
        assert 0 <= p["cone_angle_stderr_rad"] < 0.05 * p["cone_angle_rad"]  # halves analysed apart
    assert fit["model"] == "cone-angle" and len(fit["predicted_rad"]) == len(ok)
    for p, predicted in zip(ok, fit["predicted_rad"], strict=True):
        assert predicted == pytest.approx(p["model_cone_angle_rad"], rel=0.05)
    session = out["session"]
    meta = json.loads((tmp_path / session.rsplit("/", 1)[-1] / "run.json").read_text())
    assert meta["analyses"] == {"laser": LASER_ANALYSIS.version}  # the analysis that made its points
    size = sum(f.stat().st_size for f in (tmp_path / session.rsplit("/", 1)[-1]).rglob("*") if f.is_file())
    assert size < 20e6
    replay = subprocess.run([sys.executable, "-m", "labkit", "replay", session],
                            capture_output=True, text=True, timeout=120)
    assert replay.returncode == 0, replay.stderr
    assert "results identical" in replay.stdout + replay.stderr
