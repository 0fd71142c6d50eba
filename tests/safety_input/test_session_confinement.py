"""Issue 17, deliver 6: files stay in their session. Device roles are plain names in rig files
and in a session's rig copy; every path a session reads or writes lies inside it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.session import SessionError
from labkit.session.paths import session_file

from .conftest import FIG525, assert_one_line, killed_copy, run_cli

BAD_ROLES = ["../../../other/S/events", "/tmp/labkit-escape", "Rotor", "rotor-tach", "", "a" * 65, "x/../y"]


def files_under(path: Path) -> set[Path]:
    return {p for p in path.rglob("*")}


@pytest.mark.parametrize("role", BAD_ROLES)
def test_role_that_is_a_path_is_refused_before_anything_is_written(role, tmp_path, capsys):
    other = tmp_path / "other" / "S"
    other.mkdir(parents=True)
    (other / "events.jsonl").write_text('{"type":"start"}\n')
    text = FIG525.read_text().replace("[devices.balance]", f"[devices.{json.dumps(role)}]")
    rig = tmp_path / "sessions" / "a" / "b" / "rig.toml"
    rig.parent.mkdir(parents=True)
    rig.write_text(text)
    before = files_under(tmp_path)
    argv = ["run", rig, "speed-sweep", "--sessions", tmp_path / "sessions", "--no-progress"]
    code, out, err = run_cli(argv, capsys)
    assert_one_line(code, err, f"{rig}:devices.{role}:", "must be lower-case letters")
    assert files_under(tmp_path) == before
    assert (other / "events.jsonl").read_text() == '{"type":"start"}\n'


def test_session_rig_copy_with_a_path_role_is_refused_on_resume(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path)
    rig = session / "rig.toml"
    rig.write_text(rig.read_text().replace("[devices.balance]", '[devices."../../../escaped"]'))
    before = files_under(tmp_path)
    code, out, err = run_cli(["run", "--resume", session, "--sessions", tmp_path / "new", "--no-progress"],
                             capsys)
    assert_one_line(code, err, "rig.toml:devices.../../../escaped:")
    assert files_under(tmp_path) - before <= {session / ".resume.lock"}


def test_run_json_pointing_the_rig_outside_is_refused(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path)
    (tmp_path / "outside.toml").write_text(FIG525.read_text())
    meta = json.loads((session / "run.json").read_text())
    meta["rig_file"] = "../outside.toml"
    (session / "run.json").write_text(json.dumps(meta))
    code, out, err = run_cli(["run", "--resume", session, "--sessions", tmp_path / "new", "--no-progress"],
                             capsys)
    assert_one_line(code, err, "leads outside the session")
    assert not (tmp_path / "new").exists()


def test_symlink_out_of_a_session_is_not_followed(complete_session, tmp_path, capsys):
    session = killed_copy(complete_session, tmp_path)
    outside = tmp_path / "secret.jsonl"
    outside.write_text('{"type":"point","point":{"step":3}}\n')
    (session / "events.jsonl").unlink()
    (session / "events.jsonl").symlink_to(outside)
    code, out, err = run_cli(["run", "--resume", session, "--dry-run"], capsys)
    assert_one_line(code, err, "events.jsonl", "leads outside the session")


@settings(max_examples=300, deadline=None)
@given(st.lists(st.text(max_size=12), min_size=1, max_size=3))
def test_session_file_never_leaves_the_session(tmp_path_factory, parts):
    root = tmp_path_factory.getbasetemp() / "fuzz-session"
    root.mkdir(exist_ok=True)
    try:
        path = session_file(root, *parts)
    except SessionError as exc:
        assert str(root) in str(exc)
        return
    assert root.resolve() in path.parents


@pytest.mark.parametrize("argv_of, linked", [
    (lambda s, tmp: ["replay", s, "--export-csv"], "readings/balance.jsonl"),
    (lambda s, tmp: ["fit", s, "--model", "power-law"], "results.json"),
    (lambda s, tmp: ["report", s, "--out", tmp / "report"], "results.json"),
], ids=["export-csv", "fit", "report"])
def test_session_files_that_are_symlinks_out_are_refused(argv_of, linked, complete_session, tmp_path, capsys):
    import shutil

    session = tmp_path / "S"
    shutil.copytree(complete_session, session)
    secret = tmp_path / "secret.json"
    secret.write_text(json.dumps({"points": [{"speed_rpm": 1.0, "force_g": 1.0}]}))
    (session / linked).unlink()
    (session / linked).symlink_to(secret)
    code, out, err = run_cli(argv_of(session, tmp_path), capsys)
    assert_one_line(code, err, "leads outside the session")
