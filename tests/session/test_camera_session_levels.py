"""A camera session at the analysis-only level (a real-clock one replays faithfully:
tests/session/test_camera_faithful_replay.py): cone-sweep's bursts are analysed again from the
frame cassette; a protocol without an analysis rule (strobe-sweep) says its points were taken as
recorded rather than claiming it recomputed them (issue 23)."""

import json
import shutil
from pathlib import Path

from labkit.cli import main

SESSIONS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"


def _as_real_clock(name: str, tmp_path: Path) -> Path:
    session = tmp_path / name
    shutil.copytree(SESSIONS / name, session)
    meta = json.loads((session / "run.json").read_text())
    meta["clock"] = "real"  # as a lab's camera session records it
    (session / "run.json").write_text(json.dumps(meta))
    (session / "clock.jsonl").write_text("")
    return session


def test_a_real_clock_cone_sweep_is_re_analysed_from_its_frames(capsys):
    assert main(["replay", "--analysis-only", str(SESSIONS / "real-cone-sweep")]) == 0
    captured = capsys.readouterr()
    assert "replay level: analysis only" in captured.out
    assert "3 points and the fit recomputed from the recorded bytes" in captured.out


def test_the_re_analysed_cone_angle_is_held_against_results_json(tmp_path, capsys):
    session = _as_real_clock("cone-sweep-clean", tmp_path)
    results = json.loads((session / "results.json").read_text())
    results["points"][2]["cone_angle_rad"] *= 1.05  # not what the frames give, in both files
    (session / "results.json").write_text(json.dumps(results))
    events = [json.loads(line) for line in (session / "events.jsonl").read_text().splitlines()]
    for event in events:
        if event.get("type") == "point" and event["point"].get("step") == 2:
            event["point"]["cone_angle_rad"] = results["points"][2]["cone_angle_rad"]
    (session / "events.jsonl").write_text("".join(json.dumps(e) + "\n" for e in events))
    assert main(["replay", "--analysis-only", str(session)]) == 1
    assert "points[2].cone_angle_rad" in capsys.readouterr().err


def test_a_protocol_without_an_analysis_rule_says_its_points_were_taken_as_recorded(tmp_path, capsys):
    session = _as_real_clock("strobe-sweep-clean", tmp_path)
    assert main(["replay", "--analysis-only", str(session)]) == 0
    captured = capsys.readouterr()
    assert "no analysis-only rule for protocol 'strobe-sweep'" in captured.err
    assert "points taken as recorded" in captured.out
    assert "recomputed from the recorded bytes" not in captured.out
