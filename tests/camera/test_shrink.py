"""`labkit shrink`: the committed cone-sweep session thinned and scaled into a smaller fixture whose
results are recomputed from the shrunk bytes and replay exactly."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from labkit.devices.camera.cassette import read_cassette
from labkit.devices.camera.shrink import Shrink, shrink_image
from labkit.protocols.replay import replay_session

from .loopback import numbered_jpeg

SESSION = Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "cone-sweep-clean"


def test_shrink_thins_scales_recomputes_and_replays(tmp_path):
    out = tmp_path / "small"
    done = subprocess.run([sys.executable, "-m", "labkit", "shrink", str(SESSION), str(out), "--every", "2",
                           "--scale", "0.5"], capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["frames"] == [120, 60] and summary["frame_bytes"][1] < summary["frame_bytes"][0] / 3
    header, entries, _ = read_cassette(out / "cassettes" / "camera.jsonl")
    assert header["settings"]["size"] == "160x120" and header["shrunk"]["every"] == 2
    _, original, _ = read_cassette(SESSION / "cassettes" / "camera.jsonl")
    last = {}
    for e in original:
        last[e["step"]] = e["t_host"]
    assert {e["step"]: e["t_host"] for e in entries} == last  # every burst still ends when it did
    params = json.loads((out / "run.json").read_text())["params"]
    assert params["burst_frames"] == 10 and params["mm_per_px"] == 4.0
    points = json.loads((out / "results.json").read_text())["points"]
    assert all(p["frames"] == 10 for p in points)
    for p in points:
        if p["verdict"] == "ok":
            assert p["cone_angle_rad"] == pytest.approx(p["model_cone_angle_rad"], rel=0.05)
    assert replay_session(out).identical


def test_shrink_refuses_an_existing_folder_and_a_bad_crop(tmp_path):
    done = subprocess.run([sys.executable, "-m", "labkit", "shrink", str(SESSION), str(tmp_path)],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "already exists" in done.stderr
    with pytest.raises(ValueError, match="reaches beyond the 320x240 frame"):
        shrink_image(numbered_jpeg(0), Shrink(crop=(300, 0, 100, 100)))
    with pytest.raises(ValueError, match="scale must be in"):
        Shrink(scale=1.5).check()
