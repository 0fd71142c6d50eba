"""Sessions survive SIGKILL, resume as a linked run, and Ctrl-C leaves a resumable session."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.session import load_session_record, read_jsonl

REPO = Path(__file__).resolve().parents[2]
RIG = str(REPO / "rigs" / "emulated-fig525.toml")
SWEEP = ["--set", "speeds_rpm=6000:12000:2000", "--set", "record_s=1.0", "--no-progress"]


def labkit(*args):
    return [sys.executable, "-m", "labkit", *args]


def wait_for_points(root: Path, n: int, proc: subprocess.Popen, timeout: float = 60.0) -> Path:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.stderr.read()
        for events in root.glob("*/events.jsonl"):
            if sum(1 for e in read_jsonl(events) if e["type"] == "point") >= n:
                return events.parent
        time.sleep(0.05)
    raise AssertionError(f"no {n} points within {timeout} s")


def test_sigkill_mid_sweep_leaves_a_readable_session_that_resume_completes(tmp_path):
    proc = subprocess.Popen(labkit("run", RIG, "speed-sweep", "--sessions", str(tmp_path), *SWEEP),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    session = wait_for_points(tmp_path, 2, proc)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=10)

    record = load_session_record(session)
    assert record.meta["status"] == "running"          # it never got to write its end
    points = record.completed_points()
    assert len(points) >= 2
    # every reading up to the last flushed event is on disk: each point's balance readings
    readings = record.readings("balance")
    for event in (e for e in record.events if e["type"] == "point"):
        step = next(e for e in record.events if e["type"] == "step" and e["index"] == event["index"])
        in_step = [r for r in readings if step["t"] <= r["t"] <= event["t"]]
        assert len(in_step) >= event["point"]["n"]
    assert (session / "cassettes" / "rotor_motor.jsonl").stat().st_size > 0

    # resume through the same CLI entry point, in-process (a second interpreter start costs ~10 s on CI)
    assert main(["run", "--resume", str(session), "--sessions", str(tmp_path), "--no-progress"]) == 0
    resumed = [p for p in tmp_path.iterdir() if p != session]
    assert len(resumed) == 1
    meta = json.loads((resumed[0] / "run.json").read_text())
    assert meta["resumed_from"] == str(session) and meta["status"] == "completed"
    results = json.loads((resumed[0] / "results.json").read_text())
    assert [p["step"] for p in results["points"]] == [0, 1, 2, 3]
    assert results["points"][: len(points)] == points     # carried over unchanged
    assert results["fit"]["params"]["b"]["value"] == pytest.approx(-2.0, abs=0.1)


def test_ctrl_c_stops_the_cli_run_safely_and_it_can_be_resumed(tmp_path):
    proc = subprocess.Popen(labkit("run", RIG, "speed-sweep", "--sessions", str(tmp_path), *SWEEP),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    session = wait_for_points(tmp_path, 1, proc)
    os.kill(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130
    assert "resume with: labkit run --resume" in err
    record = load_session_record(session)
    assert record.meta["status"] == "interrupted"
    kinds = [e["type"] for e in record.events]
    assert "stop_request" in kinds and kinds[-1] == "stop"
    results = json.loads((session / "results.json").read_text())
    assert results["points"] == record.completed_points()


def test_torn_last_line_of_a_killed_run_is_skipped(tmp_path):
    (tmp_path / "run.json").write_text(json.dumps({"protocol": "speed-sweep", "params": {}}))
    (tmp_path / "events.jsonl").write_text('{"type":"start","t":0}\n{"type":"poi')
    assert [e["type"] for e in load_session_record(tmp_path).events] == ["start"]
