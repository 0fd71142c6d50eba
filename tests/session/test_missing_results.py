"""A session whose steps all finished but whose results.json is missing (issue 27): `labkit
report` and `labkit fit` take the results from events.jsonl and say so; `--resume` says what is
missing and what to run; a session with no point is refused with the reason."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from labkit.cli import main
from labkit.session import load_session_record
from labkit.session.recover import results_from_events

SESSIONS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"


def _without_results(tmp_path: Path, keep_lines: int | None = None) -> Path:
    session = tmp_path / "s"
    shutil.copytree(SESSIONS / "speed-sweep-clean", session)
    (session / "results.json").unlink()
    if keep_lines is not None:  # killed before its end: the results event not written
        events = session / "events.jsonl"
        events.write_text("\n".join(events.read_text().splitlines()[:keep_lines]) + "\n")
    return session


def test_report_uses_the_results_event(tmp_path, capsys):
    session = _without_results(tmp_path)
    assert main(["report", str(session)]) == 0
    err = capsys.readouterr().err
    assert f"results.json is missing (deleted, or the run was killed after its last point); using the " \
           f"results event at {session / 'events.jsonl'}:115" in err, err
    report = (session / "report" / "report.md").read_text()
    assert "## Data" in report and "| 3 | 0 | 18000 |" in report and "### Power law" in report, report


def test_fit_takes_the_points_when_the_run_ended_before_its_results(tmp_path, capsys):
    session = _without_results(tmp_path, keep_lines=114)  # the 4 points, no results event
    assert main(["fit", str(session)]) == 0
    err = capsys.readouterr().err
    assert "using the 4 points in events.jsonl and run.json (the run ended before its results" in err, err
    recorded = json.loads((SESSIONS / "speed-sweep-clean" / "results.json").read_text())
    found = results_from_events(load_session_record(session))
    assert found is not None and found[0]["points"] == recorded["points"]


def test_resume_says_only_results_json_is_missing(tmp_path, capsys):
    session = _without_results(tmp_path)
    assert main(["run", "--resume", str(session), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert "all 4 steps are already done; only its results.json is missing" in err, err
    assert f"labkit report {session}" in err, err


def test_a_session_without_points_is_refused_with_the_reason(tmp_path, capsys):
    session = _without_results(tmp_path, keep_lines=2)
    assert main(["report", str(session)]) != 0
    err = capsys.readouterr().err
    assert "results.json: missing, and events.jsonl holds no point" in err, err
