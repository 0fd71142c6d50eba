"""A camera session at the analysis-only level (a real-clock one replays faithfully:
tests/session/test_camera_faithful_replay.py): cone-sweep's and strobe-sweep's bursts are
analysed again from the frame cassette (strobe-sweep with the status lines kept in
readings/strobe.jsonl); a session the rule cannot re-analyse says its points were taken as
recorded rather than claiming it recomputed them (issue 23)."""

import json
import shutil
from pathlib import Path

from session_edits import scale_point, without_digests

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
    scale_point(session, 2, "cone_angle_rad", 1.05)  # not what the frames give
    assert main(["replay", "--analysis-only", str(session)]) == 1
    assert "points[2].cone_angle_rad" in capsys.readouterr().err


def test_a_real_clock_strobe_sweep_is_re_analysed_from_its_frames_and_status_lines(tmp_path, capsys):
    session = _as_real_clock("strobe-sweep-clean", tmp_path)
    assert main(["replay", "--analysis-only", str(session)]) == 0
    captured = capsys.readouterr()
    assert "4 points and the fit recomputed from the recorded bytes" in captured.out
    assert "taken as recorded" not in captured.out + captured.err


def test_an_edited_phi_is_named_by_the_strobe_rule(tmp_path, capsys):
    session = _as_real_clock("strobe-sweep-clean", tmp_path)
    without_digests(session)
    scale_point(session, 2, "phi_rad", 1.05)  # not what the frames give
    assert main(["replay", "--analysis-only", str(session)]) == 1
    assert "points[2].phi_rad" in capsys.readouterr().err


def test_an_edited_strobe_status_line_is_named(tmp_path, capsys):
    """The rotor frequency of every status line raised by 1 Hz in readings/strobe.jsonl (value
    untouched): the re-analysis uses the lines' bytes, so the points' f_rot no longer match."""
    session = _as_real_clock("strobe-sweep-clean", tmp_path)
    without_digests(session)
    path = session / "readings" / "strobe.jsonl"
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    for row in rows:
        fields = row["raw"].split(",")
        fields[3] = f"{float(fields[3]) + 1.0:.4f}"
        row["raw"] = ",".join(fields)
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    assert main(["replay", "--analysis-only", str(session)]) == 1
    assert "points[0].rotor_hz" in capsys.readouterr().err


def test_a_strobe_session_without_status_lines_says_its_points_were_taken_as_recorded(tmp_path, capsys):
    """A strobe-sweep recorded before labkit kept the status lines cannot be re-analysed: it says
    so rather than claiming it recomputed its points."""
    session = _as_real_clock("strobe-sweep-clean", tmp_path)
    without_digests(session)
    (session / "readings" / "strobe.jsonl").unlink()
    (session / "readings" / "strobe.parquet").unlink(missing_ok=True)
    assert main(["replay", "--analysis-only", str(session)]) == 0
    captured = capsys.readouterr()
    assert "no strobe status lines in" in captured.err
    assert "points taken as recorded" in captured.out
    assert "recomputed from the recorded bytes" not in captured.out
