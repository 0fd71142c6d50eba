"""The safety matrix (issue 17): one test per exit path, as a lab meets it.

The shipped emulated Fig. 5.25 rig is served by `labkit emulate` in its own process, so the
emulated controller keeps doing what it was last told when labkit dies, as a real one does;
`labkit run` drives it over its pseudo-terminals at 12 000 RPM, as a user starts it (with the
supervisor it starts for real ports). After each way of ending the run the rotor, read from
its own tachometer, must be below 300 RPM 3 s later, with no traceback (docs/explanation/safety.md).
"""

from __future__ import annotations

import json
import os
import signal
import sys

import pytest

from labkit.cli import main
from labkit.io.cassette import load_cassette
from labkit.session import load_session_record

from .harness import EmulatedRig, wait_for

pytestmark = [pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ptys, prlimit, /proc"),
              pytest.mark.timeout(180)]

STOPPED_RPM = 300.0
AFTER_S = 3.0


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """One `labkit emulate` for the matrix (each test leaves the rotor stopped)."""
    with EmulatedRig(tmp_path_factory.mktemp("lab")) as rig:
        yield rig


def assert_clean(stderr: str) -> None:
    assert "Traceback" not in stderr, stderr
    assert stderr.strip(), "a stopped run says why"


@pytest.mark.parametrize("name", ["SIGTERM", "SIGHUP", "SIGQUIT"])
def test_stop_signal_to_labkit_run_stops_the_rotor(lab, tmp_path, name):
    run = lab.start_run(tmp_path)
    sent = run.signal_when_holding(name)
    stderr = run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: {name} to labkit run: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"{name}: rotor at {rpm:.0f} RPM {AFTER_S} s later"
    assert run.proc.returncode == 130
    assert_clean(stderr)
    assert f"stopped by {name}" in stderr and "resume with: labkit run --resume" in stderr
    meta = run.run_json()
    assert meta["status"] == "interrupted" and meta["signal"] == name


def test_ctrl_c_typed_on_the_terminal_stops_the_rotor_once(lab, tmp_path):
    # the terminal's Ctrl-C reaches supervisor and worker; it must count once, not twice
    run = lab.start_run(tmp_path, terminal=True)
    sent = run.type_on_terminal(b"\x03")
    stderr = run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: Ctrl-C on the terminal: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {AFTER_S} s later"
    assert_clean(stderr)
    assert "stopped by Ctrl-C at a checkpoint" in stderr and run.proc.returncode == 130
    assert [e["count"] for e in run.events() if e["type"] == "stop_request"] == [1]


def test_terminal_closed_stops_the_rotor(lab, tmp_path):
    run = lab.start_run(tmp_path, terminal=True)
    sent = run.close_terminal()
    run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: terminal closed: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {AFTER_S} s later"
    meta = wait_for(lambda: (m := run.run_json())["status"] != "running" and m, 30, "session closed")
    assert meta["status"] == "interrupted" and meta["signal"] == "SIGHUP"


def test_sigkill_of_labkit_run_stops_the_rotor(lab, tmp_path):
    # the supervisor (the PID the user sees) dies: the worker gets SIGTERM from the kernel
    run = lab.start_run(tmp_path)
    sent = run.signal_when_holding("SIGKILL")
    run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: SIGKILL to labkit run: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {AFTER_S} s later"
    wait_for(lambda: run.run_json()["status"] == "interrupted", 30, "the worker closed the session")
    assert "supervisor" not in run.run_json()["reason"]


def test_sigkill_of_the_worker_the_supervisor_stops_the_rotor(lab, tmp_path):
    # what the OOM killer does: the process with the ports dies without a word
    run = lab.start_run(tmp_path)
    sent = run.signal_when_holding("SIGKILL", target="worker")
    stderr = run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: SIGKILL to the worker: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {AFTER_S} s later"
    assert_clean(stderr)
    assert "was killed by SIGKILL; the supervisor commanded rotor_motor to zero" in stderr
    assert run.proc.returncode == 128 + signal.SIGKILL
    # the session the worker could not close is closed by the supervisor, and stays resumable
    meta = run.run_json()
    assert meta["status"] == "killed", meta
    assert "killed by SIGKILL" in meta["reason"] and meta["ended"]
    assert f"recorded as killed; resume with: labkit run --resume {run.session()}" in stderr


def test_sigkill_of_every_labkit_process_leaves_the_controllers_watchdog(lab, tmp_path):
    # nothing of labkit is left: only the controller's command timeout (rig: 500 ms) can stop it
    run = lab.start_run(tmp_path)
    sent = run.signal_when_holding("SIGKILL", target="group")
    run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: SIGKILL to every labkit process: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {AFTER_S} s later"


def test_full_sessions_disk_stops_the_rotor_and_keeps_a_valid_session(lab, tmp_path):
    run = lab.start_run(tmp_path)
    sent = run.fill_disk_when_holding()
    stderr = run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: sessions disk full: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {AFTER_S} s later"
    assert_clean(stderr)
    first = stderr.strip().splitlines()[0]
    assert first.startswith("labkit run: failed: ") and "cannot write " in first
    assert "File too large" in first  # the cause, as the OS said it (ENOSPC on a real full disk)
    assert run.proc.returncode == 2
    session = run.session()
    record = load_session_record(session)               # what was written stays valid ...
    assert record.events[0]["type"] == "start"
    for cassette in (session / "cassettes").glob("*.jsonl"):
        assert load_cassette(cassette).events     # ... every cassette line whole ...
    assert main(["run", "--resume", str(session), "--dry-run"]) == 0   # ... and resumable


@pytest.fixture
def small_disk(tmp_path):
    """A 4 MB tmpfs for the sessions (needs root and mount; skipped elsewhere)."""
    import subprocess as sp

    mount = tmp_path / "disk"
    mount.mkdir()
    if os.geteuid() != 0 or sp.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(mount)],
                                   capture_output=True).returncode != 0:
        pytest.skip("needs root to mount a small tmpfs")
    try:
        yield mount
    finally:
        sp.run(["umount", "-l", str(mount)], check=False)


def test_really_full_disk_enospc_stops_the_rotor(lab, small_disk):
    run = lab.start_run(small_disk / "sessions")
    sent = run.fill_filesystem_when_holding(small_disk / "filler")
    stderr = run.finish()
    rpm = lab.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: tmpfs full (ENOSPC): rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm < STOPPED_RPM, f"rotor at {rpm:.0f} RPM {AFTER_S} s later"
    assert_clean(stderr)
    first = stderr.strip().splitlines()[0]
    assert "cannot write " in first and "No space left on device" in first, first
    (small_disk / "filler").unlink()          # room again: the session is whole and resumable
    assert load_session_record(run.session()).events[0]["type"] == "start"
    assert main(["run", "--resume", str(run.session()), "--dry-run"]) == 0


def test_controller_unplugged_says_the_stop_could_not_be_delivered(tmp_path):
    with EmulatedRig(tmp_path, unplug=("rotor_motor",)) as rig:
        run = rig.start_run(tmp_path / "sessions")
        run.wait_holding()
        rig.unplug()
        stderr = run.finish()
    assert_clean(stderr)
    assert "could not stop rotor_motor: port gone" in stderr and "cut the motor's power" in stderr
    assert "resume with" not in stderr
    assert run.proc.returncode == 3
    meta = run.run_json()
    assert "port gone" in meta["stop_failed"]["rotor_motor"]
    assert any(e["type"] == "stop_failed" for e in run.events())


def test_second_run_on_a_busy_port_is_refused(lab, tmp_path):
    first = lab.start_run(tmp_path / "first")
    first.wait_holding()
    second = lab.start_run(tmp_path / "second")
    stderr = second.finish()
    worker = first.worker()
    assert second.proc.returncode == 2
    assert_clean(stderr)
    assert "port busy, held by PID " + str(worker) in stderr
    assert not (tmp_path / "second").exists() or not any((tmp_path / "second").iterdir())
    sent = first.signal_when_holding("SIGTERM")   # the first run never noticed
    first.finish()
    assert lab.rotor_rpm_at(sent + AFTER_S) < STOPPED_RPM
    kinds = [e["type"] for e in first.events()]
    assert "interlock" not in kinds and first.run_json()["status"] == "interrupted"
    assert json.loads((first.session() / "run.json").read_text())["signal"] == "SIGTERM"


def test_without_the_controllers_watchdog_sigkill_of_everything_leaves_it_spinning(tmp_path):
    # why rig files must declare the watchdog: the same kill with the controller's timeout off
    # (the SMC's factory default) - and proof that this matrix's tachometer check can fail
    with EmulatedRig(tmp_path, watchdog_ms=0) as rig:
        run = rig.start_run(tmp_path / "sessions")
        sent = run.signal_when_holding("SIGKILL", target="group")
        run.finish()
        rpm = rig.rotor_rpm_at(sent + AFTER_S)
    print(f"matrix: SIGKILL to everything, watchdog off: rotor {rpm:.0f} RPM {AFTER_S:.0f} s later")
    assert rpm > 10000, f"rotor at {rpm:.0f} RPM: expected it still turning"
