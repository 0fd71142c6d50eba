"""A supervisor closes only the sessions of the process that died (labkit.session.orphans)."""

from __future__ import annotations

import json
import os

from labkit.session import Session
from labkit.session.orphans import close_killed_sessions


def _session(root, **meta_changes):
    s = Session.create(root, protocol="speed-sweep", params={}, rig_name="r", rig_text="", clock="virtual")
    if meta_changes:
        s.update_meta(**meta_changes)
    return s


def test_only_the_dead_processes_running_session_is_closed(tmp_path):
    mine = _session(tmp_path)
    assert mine.meta["pid"] == os.getpid()
    other_pid = _session(tmp_path, pid=os.getpid() + 1)
    done = _session(tmp_path, status="completed")
    (tmp_path / "not-a-session").mkdir()
    (tmp_path / "not-a-session" / "run.json").write_text("{torn")

    closed = close_killed_sessions(tmp_path, os.getpid(), "the run process was killed by SIGKILL")

    assert closed == [mine.path]
    meta = json.loads((mine.path / "run.json").read_text())
    assert meta["status"] == "killed" and "SIGKILL" in meta["reason"] and meta["ended"]
    assert json.loads((other_pid.path / "run.json").read_text())["status"] == "running"
    assert json.loads((done.path / "run.json").read_text())["status"] == "completed"


def test_a_second_call_finds_nothing_left(tmp_path):
    _session(tmp_path)
    assert len(close_killed_sessions(tmp_path, os.getpid(), "why")) == 1
    assert close_killed_sessions(tmp_path, os.getpid(), "why") == []
