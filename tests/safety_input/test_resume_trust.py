"""Issue 17, deliver 7: resume that can be trusted. Recorded points are checked against the
plan, damaged lines are reported as file:line, a changed rig may change ports only, a run that
fails before its first step keeps no session, and one process resumes a session at a time."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import FIG525, REPO, assert_one_line, killed_copy, run_cli


def resume(session: Path, root: Path, capsys, *extra) -> tuple[int, str, str, Path | None]:
    argv = ["run", "--resume", session, "--sessions", root, "--no-progress", *extra]
    code, out, err = run_cli(argv, capsys)
    new = [p for p in root.iterdir()] if root.exists() else []
    return code, out, err, (new[0] if len(new) == 1 else None)


def result_steps(session: Path) -> list[int]:
    return [p["step"] for p in json.loads((session / "results.json").read_text())["points"]]


def append_event(session: Path, line: str) -> int:
    events = session / "events.jsonl"
    text = events.read_text()
    events.write_text(text + line + "\n")
    return text.count("\n") + 1


def test_clean_resume_carries_two_points_and_measures_two(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    code, out, err, new = resume(session, tmp_path / "new", capsys)
    assert code == 0 and err == "", err
    assert result_steps(new) == [0, 1, 2, 3]
    assert not (session / ".resume.lock").exists()          # the old session is left as found


def test_phantom_point_is_ignored_with_its_line(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    line = append_event(session, json.dumps({"type": "point", "index": 99, "point": {
        "step": 99, "direction": "up", "repeat": 0, "target_rpm": 30000.0, "force_g": 1.0}}))
    code, out, err, new = resume(session, tmp_path / "new", capsys)
    assert code == 0, err
    assert f"events.jsonl:{line}: point with step 99 is outside the plan (steps 0 to 3); ignored" in err
    assert "completed 4 points" in out
    assert result_steps(new) == [0, 1, 2, 3]


def test_duplicated_point_is_measured_again_not_counted_twice(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    points = [json.loads(x) for x in (session / "events.jsonl").read_text().splitlines()]
    second = next(e for e in points if e["type"] == "point" and e["point"]["step"] == 1)
    append_event(session, json.dumps(second))
    code, out, err, new = resume(session, tmp_path / "new", capsys)
    assert code == 0, err
    assert "step 1 is recorded 2 times" in err and "measured again" in err
    assert result_steps(new) == [0, 1, 2, 3]
    meta = json.loads((new / "run.json").read_text())
    assert [p["step"] for p in meta["carried_points"]] == [0]
    assert any("recorded 2 times" in w for w in meta["resume_warnings"])


def test_point_whose_parameters_differ_from_the_plan_is_dropped(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    events = session / "events.jsonl"
    events.write_text(events.read_text().replace('"target_rpm":8000.0', '"target_rpm":9000.0'))
    code, out, err, new = resume(session, tmp_path / "new", capsys)
    assert code == 0, err
    assert "point with step 1 has target_rpm 9000.0, the plan says 8000.0" in err
    points = json.loads((new / "results.json").read_text())["points"]
    assert [(p["step"], p["target_rpm"]) for p in points] == [(0, 6000.0), (1, 8000.0), (2, 10000.0),
                                                                (3, 12000.0)]


def test_junk_line_in_the_middle_of_events_is_reported_and_skipped(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    events = session / "events.jsonl"
    lines = events.read_bytes().splitlines(keepends=True)
    events.write_bytes(b"".join(lines[:10]) + b"\xff\xfe\x00junk\x80\n" + b"".join(lines[10:]))
    code, out, err, new = resume(session, tmp_path / "new", capsys)
    assert code == 0 and "Traceback" not in err
    assert "events.jsonl:11: damaged line skipped (not UTF-8 text" in err
    assert result_steps(new) == [0, 1, 2, 3]


def test_torn_last_line_is_skipped_silently(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    with open(session / "events.jsonl", "a") as f:
        f.write('{"type":"point","index":2,"point":{"st')
    code, out, err, new = resume(session, tmp_path / "new", capsys)
    assert code == 0 and err == "", err
    assert result_steps(new) == [0, 1, 2, 3]


def test_resume_with_a_rig_that_changes_ports_only(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    text = (session / "rig.toml").read_text()
    where = "seed=3&plant=model-fig525&role=balance"
    moved = text.replace(where, where + "&x=1") \
        .replace("baudrate = 9600, timeout = 0.5", "baudrate = 9600, timeout = 0.7")
    assert moved != text
    fixed = tmp_path / "fixed.toml"
    fixed.write_text(moved)
    code, out, err, new = resume(session, tmp_path / "new", capsys, "--rig", fixed)
    assert code == 0, err
    assert (new / "rig.toml").read_text() == moved
    assert result_steps(new) == [0, 1, 2, 3]


def test_resume_with_a_rig_that_changes_limits_or_bodies_is_refused(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    text = (session / "rig.toml").read_text()
    for old, new_text, named in (("max_speed_rpm = 24000", "max_speed_rpm = 20000",
                                  "limits (max_speed_rad_s: "),
                                 ("mass_g = 13.36", "mass_g = 14", "bodies (floator.mass_kg: "),
                                 ('protocol = "mtsics"', 'protocol = "and_std"', "devices.balance.protocol")):
        fixed = tmp_path / "fixed.toml"
        fixed.write_text(text.replace(old, new_text))
        code, out, err, new = resume(session, tmp_path / "new", capsys, "--rig", fixed)
        assert_one_line(code, err, "only ports and serial settings may change", named)
        assert new is None


def test_run_that_fails_before_its_first_step_keeps_no_session(tmp_path, capsys):
    text = FIG525.read_text().replace('port = "sim://labkit_tach?seed=2&plant=model-fig525&role=rotor_tach&rate_hz=20"',
                                      'port = "socket://127.0.0.1:1"')
    rig = tmp_path / "rig.toml"
    rig.write_text(text)
    root = tmp_path / "sessions"
    code, out, err = run_cli(["run", rig, "speed-sweep", "--sessions", root, *(
        "--set", "speeds_rpm=6000", "--no-progress")], capsys)
    assert code == 2 and "Traceback" not in err
    assert "before the first step: nothing measured, no session kept" in err
    assert "resume with" not in err
    assert list(root.iterdir()) == []


HOLD_LOCK = """
import sys
from pathlib import Path
from labkit.protocols.resume import ResumeLock
lock = ResumeLock(Path(sys.argv[1])).acquire()
print("locked", flush=True)
sys.stdin.readline()
lock.release()
"""


def test_one_session_is_resumed_by_one_process_at_a_time(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    holder = subprocess.Popen([sys.executable, "-c", HOLD_LOCK, str(session)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True, cwd=REPO)
    try:
        assert holder.stdout.readline().strip() == "locked"
        code, out, err, new = resume(session, tmp_path / "new", capsys)
        assert_one_line(code, err, f"session {session} is being resumed by PID {holder.pid}")
        assert new is None
    finally:
        holder.communicate("\n", timeout=30)
    code, out, err, new = resume(session, tmp_path / "new", capsys)   # released: resumes
    assert code == 0, err
    assert result_steps(new) == [0, 1, 2, 3]


def test_phantom_carried_point_in_run_json_is_ignored(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    meta = json.loads((session / "run.json").read_text())
    meta["carried_points"] = [{"step": "x"}, {"step": 7, "target_rpm": 1.0}]
    (session / "run.json").write_text(json.dumps(meta))
    code, out, err, new = resume(session, tmp_path / "new", capsys)
    assert code == 0, err
    assert "run.json:carried_points[0]: a point without an integer step; ignored" in err
    assert "run.json:carried_points[1]: point with step 7 is outside the plan" in err
    assert result_steps(new) == [0, 1, 2, 3]
    code, out, err = run_cli(["replay", new], capsys)     # the new session replays: nothing carried
    assert code == 0 and "Traceback" not in err, err
    meta = json.loads((new / "run.json").read_text())
    meta["carried_points"] = [{"step": "x"}]
    (new / "run.json").write_text(json.dumps(meta))
    code, out, err = run_cli(["replay", new], capsys)
    assert "Traceback" not in err
    assert "carried_points[0]: a point without an integer step; ignored" in err


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write into a read-only folder")
def test_read_only_session_is_resumed_without_a_lock(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path / "old")
    session.chmod(0o555)
    try:
        code, out, err, new = resume(session, tmp_path / "new", capsys)
    finally:
        session.chmod(0o755)
    assert code == 0, err
    assert result_steps(new) == [0, 1, 2, 3]
