"""A supervisor closes only the sessions of the process that died (labkit.session.orphans)."""

from __future__ import annotations

import json
import os
import time

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


def test_a_stale_session_whose_pid_was_reused_is_left_alone(tmp_path):
    """Issue 27: a session left `running` by a process long gone names a PID that today's worker
    got again; the worker's death must not mark that session killed."""
    from labkit.session.process import process_identity

    mine = _session(tmp_path)
    assert mine.meta["pid_start"] == process_identity(os.getpid()) is not None
    recycled = _session(tmp_path, pid_start="another-boot:12345")          # same PID, other process
    old = _session(tmp_path, pid_start=None, started="2025-01-01T00:00:00+00:00")  # before pid_start

    closed = close_killed_sessions(tmp_path, os.getpid(), "killed by SIGKILL",
                                   identity=process_identity(os.getpid()), since=time.time() - 60)

    assert closed == [mine.path]
    for stale in (recycled, old):
        assert json.loads((stale.path / "run.json").read_text())["status"] == "running"
