"""Issue 29 exit paths inside one process on the virtual clock (exact bounds): Ctrl-Z
(SIGTSTP) in a run without a supervisor, a session folder deleted mid-step, and the
heartbeat's two sides (the cross-process cases are in test_frozen_and_stopped.py)."""

from __future__ import annotations

import os
import shutil
import signal
import time

from labkit.control.heartbeat import Heartbeat, HeartbeatWatch
from labkit.emulators.plant import shared_plant
from labkit.io.clock import VirtualClock, use_clock
from labkit.protocols import ListSink, Runner
from labkit.protocols.params import resolve_params
from labkit.rig import load_rig
from labkit.session.writer import Session

from .test_exit_paths_inprocess import PERIOD, RIG, SignalledHold, fresh_plants, run_signalled  # noqa: F401


def test_ctrl_z_in_a_run_without_supervisor_takes_the_ctrl_c_path():
    before = signal.getsignal(signal.SIGTSTP)
    outcome, marks, sink, motor = run_signalled(signum=int(signal.SIGTSTP))
    assert outcome.status == "interrupted"
    assert outcome.reason == ("stopped by SIGTSTP (Ctrl-Z: a run does not pause, it stops) at a checkpoint; "
                              "motors at zero")
    zeroed = motor.zeroed_since(marks["signalled_at"])
    assert zeroed is not None and zeroed - marks["signalled_at"] <= PERIOD + 1e-9
    assert [e["signal"] for e in sink.of_type("stop_request")] == ["SIGTSTP"]
    assert signal.getsignal(signal.SIGTSTP) is before  # the shell's Ctrl-Z works again afterwards


class FolderDeletingHold(SignalledHold):
    """Hold one speed; delete the run's own session folder mid-step."""

    name = "folder-deleting-hold"

    def run_step(self, ctx, step):
        ctx.set(rotor=step.targets_rad_s["rotor"])
        ctx.settle()
        self.marks["deleted_at"] = ctx.now()
        shutil.rmtree(ctx.runner.session.path)
        ctx.sleep(5.0)
        return {}


def test_a_deleted_session_folder_stops_the_run_at_the_next_tick(tmp_path):
    proto = FolderDeletingHold()
    rig = load_rig(RIG)
    clock = VirtualClock()
    sink = ListSink()
    params = resolve_params(proto.defaults, {})
    with use_clock(clock):
        session = Session.create(tmp_path, protocol=proto.name, params=params, rig_name=rig.name,
                                 rig_text=RIG.read_text(), clock="virtual")
        outcome = Runner(proto, rig, params, clock=clock, sinks=[sink], session=session).run()
    motor = shared_plant("model-fig525").motor("rotor")
    deleted = proto.marks["deleted_at"]
    assert outcome.status == "failed"
    assert f"session folder {session.path} was deleted during the run" in outcome.reason
    assert "motors commanded to zero" in outcome.reason
    interlock = sink.of_type("interlock")[0]
    assert interlock["t"] - deleted <= PERIOD + 1e-9
    zeroed = motor.zeroed_since(deleted)
    assert zeroed is not None and zeroed - deleted <= PERIOD + 1e-9
    assert not session.path.exists()  # nothing recreated a half session


def test_heartbeat_watch_sees_silence_only_while_armed_and_awake():
    heartbeat = Heartbeat()
    watch = HeartbeatWatch(heartbeat, timeout_s=0.2)
    assert watch.frozen_for() is None            # not armed: a worker still starting up
    time.sleep(0.25)
    assert watch.frozen_for() is None
    heartbeat.arm(True)
    assert watch.frozen_for() is None            # the arming itself counts as a beat
    deadline = time.monotonic() + 0.4
    while time.monotonic() < deadline:           # beating: never frozen
        heartbeat.beat()
        assert watch.frozen_for() is None
        time.sleep(0.02)
    silent = None
    deadline = time.monotonic() + 2.0
    while silent is None and time.monotonic() < deadline:
        time.sleep(0.05)                          # silent, the watcher polling: frozen after 0.2 s
        silent = watch.frozen_for()
    assert silent is not None and 0.2 < silent < 0.5
    heartbeat.arm(False)
    assert watch.frozen_for() is None            # disarmed: motors stopped, nothing to watch


def test_heartbeat_watch_does_not_blame_the_worker_for_its_own_stop():
    # the supervisor stopped (SIGSTOP) longer than the timeout: its first poll after SIGCONT
    # measures the worker's silence afresh, as it may not have run yet either
    heartbeat = Heartbeat()
    heartbeat.arm(True)
    watch = HeartbeatWatch(heartbeat, timeout_s=0.2)
    watch.frozen_for()
    time.sleep(0.7)                               # the supervisor's own gap (> OWN_GAP_S)
    assert watch.frozen_for() is None


def test_heartbeat_is_shared_across_fork():
    heartbeat = Heartbeat()
    child = os.fork()
    if child == 0:  # pragma: no cover - the child
        heartbeat.arm(True)
        for _ in range(5):
            heartbeat.beat()
        os._exit(0)
    os.waitpid(child, 0)
    count, armed = heartbeat.read()
    assert armed and count == 6


def test_worker_pulse_beats_between_ticks_and_stops_when_a_due_tick_is_overdue():
    from labkit.control.heartbeat import TICK_STALE_S, WorkerPulse
    from labkit.control.loop import build_speed_control
    from labkit.rig import open_rig
    from labkit.units import rpm_to_rad_s

    clock = VirtualClock()
    heartbeat = Heartbeat()
    with use_clock(clock):
        opened = open_rig(load_rig(RIG), clock)
        try:
            control = build_speed_control(opened, clock)
            pulse = WorkerPulse(heartbeat, control).start()
            assert heartbeat.read()[1]                       # armed
            count = heartbeat.read()[0]
            time.sleep(0.35)                                 # no tick due yet: the thread beats
            assert heartbeat.read()[0] > count
            control.set_targets({"rotor": rpm_to_rad_s(3000.0)})
            clock.sleep(0.5)                                 # ticks run (virtual clock), each beats
            assert pulse.last_tick is not None and not pulse.tick_overdue()
            time.sleep(TICK_STALE_S + 0.2)                   # the virtual clock stands: ticks overdue
            assert pulse.tick_overdue()
            count = heartbeat.read()[0]
            time.sleep(0.35)
            assert heartbeat.read()[0] == count              # ... so nothing beats
            control.stop()                                   # stopped: no tick due, the thread beats
            time.sleep(0.35)
            assert heartbeat.read()[0] > count
            pulse.stop()
            assert not heartbeat.read()[1]                   # disarmed
        finally:
            opened.close()
