"""``labkit twin --only camera``: the cone-sweep filmed by the emulated camera on the model plant;
the Eq. 5.24 fit of the filmed points gives the model's cone angle at 6 000 RPM back inside its
95 % interval, and every ok point is within 1 % of the model's angle at its speed."""

import json
from pathlib import Path

from labkit.cli import main

RIGS = Path(__file__).resolve().parents[2] / "rigs"


def test_twin_camera_recovers_the_models_cone_angle_from_filmed_frames(tmp_path, capsys):
    code = main(["twin", str(RIGS / "emulated-fig525.toml"), "--out", str(tmp_path), "--only", "camera"])
    report = json.loads((tmp_path / "twin-report.json").read_text())
    assert code == 0, capsys.readouterr().out
    (row,) = report["rows"]
    assert row["name"] == "twin/camera/cone_angle" and row["ok"]
    lo, hi = row["ci95"]
    assert lo <= row["put_in"] <= hi
    assert 0 < hi - lo < 0.01 * row["put_in"]   # an interval that says something
    assert abs(row["rel_diff"]) < 0.005
    camera = report["runs"]["camera"]
    session = Path(camera["session"])
    points = json.loads((session / "results.json").read_text())["points"]
    assert len([p for p in points if p["verdict"] == "ok"]) >= 5
    assert camera["largest_point_rel_diff"] < 0.01
    assert (session / "cassettes" / "camera.mjpeg").stat().st_size > 0
