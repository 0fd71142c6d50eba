"""Issue 29, exit paths without a dead process: a frozen worker, a stopped-and-continued
supervisor, Ctrl-Z, and a session folder deleted mid-run.

Same lab as the matrix (tests/safety/harness.py): `labkit emulate` in its own process, `labkit
run` on its ptys at 12 000 RPM with its supervisor, the rotor read from its own tachometer.
The frozen worker runs with the controller's watchdog off, so only the supervisor can stop it.
"""

from __future__ import annotations

import signal
import sys
import time

import pytest

from labkit.control.heartbeat import HEARTBEAT_TIMEOUT_S

from .harness import HOLD_RPM, EmulatedRig, delete_session_when_holding, pause_process, wait_for

pytestmark = [pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ptys, /proc"),
              pytest.mark.timeout(180)]

STOPPED_RPM = 300.0
AFTER_S = 3.0


def assert_clean(stderr: str) -> None:
    assert "Traceback" not in stderr, stderr
    assert stderr.strip(), "a stopped run says why"


def test_sigstop_of_the_worker_the_supervisor_stops_the_rotor_without_the_watchdog(tmp_path):
    with EmulatedRig(tmp_path, watchdog_ms=0) as rig:
        run = rig.start_run(tmp_path / "sessions")
        sent = run.signal_when_holding("SIGSTOP", target="worker")
        # the supervisor sends STOP before it exits: its exit bounds the time of the STOP
        wait_for(lambda: run.proc.poll() is not None, 10, "the supervisor ends the frozen run")
        took = time.monotonic() - sent
        stderr = run.finish()
        rpm_2s = rig.rotor_rpm_at(sent + 2.0)
        rpm = rig.rotor_rpm_at(sent + HEARTBEAT_TIMEOUT_S + AFTER_S)  # the matrix's 3 s after the STOP
    print(f"frozen worker (SIGSTOP, watchdog off): supervisor stopped the motors and ended "
          f"{took:.2f} s after the signal; rotor {rpm_2s:.0f} RPM 2 s and {rpm:.0f} RPM "
          f"{HEARTBEAT_TIMEOUT_S + AFTER_S:.0f} s later")
    assert took < 2.0, f"the supervisor took {took:.2f} s"
    assert rpm_2s < 0.9 * HOLD_RPM, f"rotor still at {rpm_2s:.0f} RPM 2 s after the freeze"
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {HEARTBEAT_TIMEOUT_S + AFTER_S} s after the freeze"
    assert_clean(stderr)
    assert "stopped responding (no heartbeat for " in stderr, stderr
    assert "ended with SIGKILL; the supervisor commanded rotor_motor to zero" in stderr
    assert run.proc.returncode == 128 + signal.SIGKILL
    meta = run.run_json()
    assert meta["status"] == "killed" and "no heartbeat" in meta["reason"], meta
    assert f"recorded as killed; resume with: labkit run --resume {run.session()}" in stderr


@pytest.mark.parametrize("pause_s", [0.7, 2.0])
def test_supervisor_stopped_and_continued_the_run_goes_on(tmp_path, pause_s):
    with EmulatedRig(tmp_path) as rig:
        run = rig.start_run(tmp_path / "sessions", record_s=3.0)
        run.wait_holding()
        worker = run.worker()
        pause_process(run.proc.pid, pause_s)
        stderr = run.finish()
    assert "Traceback" not in stderr and "Errno" not in stderr, stderr
    meta = run.run_json()
    assert meta["pid"] == worker
    # the supervisor's pause neither stops the run (no signal nobody sent) nor ends the worker
    # (its silence is not the worker's): the run completes; on a loaded machine a device may
    # still time out, which is the run's own interlock, never the supervisor's doing
    assert "heartbeat" not in stderr and "stopped by" not in stderr, stderr
    assert not [e for e in run.events() if e["type"] == "stop_request"]
    if run.proc.returncode != 0:
        assert run.proc.returncode == 2 and "interlock: " in stderr, stderr
        assert meta["status"] == "failed", meta
    else:
        assert meta["status"] == "completed", meta


def test_ctrl_z_typed_on_the_terminal_stops_the_run(tmp_path):
    with EmulatedRig(tmp_path) as rig:
        run = rig.start_run(tmp_path / "sessions", terminal=True)
        sent = run.type_on_terminal(b"\x1a")
        stderr = run.finish()
        rpm = rig.rotor_rpm_at(sent + AFTER_S)
    print(f"Ctrl-Z on the terminal: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM
    assert_clean(stderr)
    assert "stopped by SIGTSTP (Ctrl-Z: a run does not pause, it stops)" in stderr, stderr
    assert run.proc.returncode == 130
    meta = run.run_json()
    assert meta["status"] == "interrupted" and meta["signal"] == "SIGTSTP"


@pytest.mark.parametrize("target", ["supervisor", "worker"])
def test_sigtstp_sent_with_kill_stops_the_run(tmp_path, target):
    with EmulatedRig(tmp_path) as rig:
        run = rig.start_run(tmp_path / "sessions")
        sent = run.signal_when_holding("SIGTSTP", target=target)
        stderr = run.finish()
        rpm = rig.rotor_rpm_at(sent + AFTER_S)
    assert rpm < STOPPED_RPM
    assert_clean(stderr)
    assert "stopped by SIGTSTP" in stderr and run.proc.returncode == 130
    assert run.run_json()["signal"] == "SIGTSTP"


def test_session_folder_deleted_stops_the_run_at_the_next_tick(tmp_path):
    with EmulatedRig(tmp_path) as rig:
        run = rig.start_run(tmp_path / "sessions")
        sent = delete_session_when_holding(run)
        stderr = run.finish()
        rpm = rig.rotor_rpm_at(sent + AFTER_S)
    print(f"session folder deleted: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM
    assert_clean(stderr)
    first = stderr.strip().splitlines()[0]
    assert first.startswith("labkit run: failed: ") and "was deleted during the run" in first, first
    assert run.proc.returncode == 2
    assert "resume with" not in stderr  # nothing left to resume
