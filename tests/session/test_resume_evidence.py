"""``labkit run --resume`` holds the points it carries against the cassettes (issue 27): an
edited point refuses the resume naming file and line; an interrupted session resumes."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from labkit.cli import main

SESSIONS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"


def _interrupted(tmp_path: Path, name: str, keep_lines: int) -> Path:
    """A copy of a recorded session cut after ``keep_lines`` events, without results.json (as a
    run killed after its last kept point leaves it; the cassettes hold more than the events)."""
    session = tmp_path / name
    shutil.copytree(SESSIONS / name, session)
    events = session / "events.jsonl"
    events.write_text("\n".join(events.read_text().splitlines()[:keep_lines]) + "\n")
    (session / "results.json").unlink()
    meta = json.loads((session / "run.json").read_text())
    (session / "run.json").write_text(json.dumps({**meta, "status": "running", "ended": None}))
    return session


def _times_ten(path: Path, number: int) -> None:
    lines = path.read_text().splitlines()
    event = json.loads(lines[number - 1])
    assert event["type"] == "point"
    event["point"]["force_g"] *= 10
    lines[number - 1] = json.dumps(event)
    path.write_text("\n".join(lines) + "\n")


def test_an_edited_point_refuses_the_resume_naming_file_and_line(tmp_path, capsys):
    session = _interrupted(tmp_path, "speed-sweep-clean", 86)  # points of steps 0-2 at lines 29, 57, 85
    _times_ten(session / "events.jsonl", 57)
    assert main(["run", "--resume", str(session), "--sessions", str(tmp_path / "new"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert f"{session / 'events.jsonl'}:57: this point does not follow from the cassettes (force_g recorded" \
        in err, err
    assert not (tmp_path / "new").exists() or not any((tmp_path / "new").iterdir())


def test_an_edited_point_of_a_real_clock_session_is_caught_within_tolerance(tmp_path, capsys):
    session = _interrupted(tmp_path, "real-speed-sweep", 81)  # points of steps 0-2 at lines 32, 56, 80
    _times_ten(session / "events.jsonl", 32)
    assert main(["run", "--resume", str(session), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert f"{session / 'events.jsonl'}:32: this point does not follow from the cassettes" in err, err
    assert "faithful replay" in err, err


def test_an_untouched_interrupted_session_resumes_with_its_points_carried(tmp_path, capsys):
    session = _interrupted(tmp_path, "speed-sweep-clean", 86)
    assert main(["run", "--resume", str(session), "--sessions", str(tmp_path / "new"), "--no-progress"]) == 0
    (new,) = (tmp_path / "new").iterdir()
    meta = json.loads((new / "run.json").read_text())
    assert [p["step"] for p in meta["carried_points"]] == [0, 1, 2]
    assert meta["resume_warnings"] == []


def test_a_cassette_with_a_negative_time_refuses_the_resume(tmp_path, capsys):
    session = _interrupted(tmp_path, "speed-sweep-clean", 86)
    cassette = session / "cassettes" / "balance.jsonl"
    lines = cassette.read_text().splitlines()
    lines[9] = json.dumps({**json.loads(lines[9]), "t": -1.0})
    cassette.write_text("\n".join(lines) + "\n")
    assert main(["run", "--resume", str(session), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert f"{cassette}:10: negative time -1.0" in err, err
