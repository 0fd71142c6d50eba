"""Exit paths over real pseudo-terminals: emulators served by PtyHost, drivers on /dev/pts/N,
a real clock and the control loop in its own thread (the closest thing to hardware in CI).

Event-driven, so they hold on a loaded machine: faults are injected when the run reports it
is holding its speed (not at a clock time after open), device timeouts are generous, and
each check is an order of events - the motor's last command is zero, received after the
cause (the STOP having left before the run returned). The exact "within one control period" bounds are checked
on the virtual clock in test_interlocks.py and tests/protocols/test_runner_safety.py.
"""

import sys
from pathlib import Path

import pytest

from labkit.emulators.plant import shared_plant
from labkit.emulators.sim_port import build_emulator
from labkit.io.clock import RealClock, use_clock
from labkit.io.pty_host import PtyHost
from labkit.protocols import ListSink, Runner
from labkit.protocols.params import resolve_params
from labkit.rig import parse_rig

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from protocols.holdproto import Hold  # noqa: E402

# generous device timeouts: a loaded CI box may starve the in-process emulators for a while;
# the emulated controller's own command timeout is off (these tests are not about it)
RIG = ((Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml").read_text()
       .replace("settle_hold_s = 1.0", "settle_hold_s = 0.2")
       .replace("tach_timeout_s = 0.5", "tach_timeout_s = 5.0")
       .replace("command_timeout_ms=500", "command_timeout_ms=0")
       .replace("options = { command_timeout_ms = 500 }", "options = { reply_timeout_s = 5.0 }"))


class OnSettled(ListSink):
    """Collects events; calls ``action()`` once, when the rotor first holds its speed."""

    def __init__(self, action=None):
        super().__init__()
        self.action = action

    def on_event(self, event):
        super().on_event(event)
        if event["type"] == "settled" and self.action is not None:
            action, self.action = self.action, None
            action()


def run_on_ptys(rig_text, on_settled=None, **overrides):
    rig = parse_rig(rig_text, "pty-rig.toml")
    clock = RealClock()
    hosts = {role: PtyHost(build_emulator(dev.port), clock=clock) for role, dev in rig.devices.items()}
    proto = Hold()
    sink = OnSettled(on_settled and (lambda: on_settled(hosts, clock)))
    params = resolve_params(proto.defaults, {"speed_rpm": 5000.0, "hold_s": 0.4, "steps": 1, **overrides})
    try:
        with use_clock(clock):
            runner = Runner(proto, rig, params, clock=clock, sinks=[sink],
                            port_override=lambda dev: hosts[dev.role].path)
            outcome = runner.run()
            marks = {**proto.marks, "returned": clock.now()}
            # the STOP left before run() returned; wait (event-driven) for the controller to read it
            motor = shared_plant("model-fig525").motor("rotor")
            deadline = clock.now() + 10.0
            while motor.duty != 0.0 and clock.now() < deadline:
                clock.sleep(0.01)
            marks["received_by"] = clock.now()
    finally:
        for host in hosts.values():
            host.close()
    for role, host in hosts.items():  # an emulator that died would look like a silent device
        assert host.error is None, (role, host.error)
    return outcome, marks, sink, shared_plant("model-fig525").motor("rotor"), hosts


def assert_stopped_between(motor, after: float, before: float) -> None:
    """The motor's last command was zero, received after ``after`` and by ``before``
    (``marks["received_by"]``: the controller read the STOP that left before run() returned)."""
    assert motor.duty == 0.0
    last_t, last_duty = motor.duty_changes[-1]
    assert last_duty == 0.0 and after <= last_t <= before, (after, last_t, before)
    assert any(duty > 0 for _, duty in motor.duty_changes), "the motor never ran"


@pytest.mark.timeout(120)
def test_normal_end_over_ptys():
    outcome, marks, sink, motor, hosts = run_on_ptys(RIG)
    assert outcome.status == "completed", outcome.reason
    assert all(h.path.startswith("/dev/pts/") for h in hosts.values())
    assert_stopped_between(motor, marks["end_0"], marks["received_by"])


@pytest.mark.timeout(120)
def test_exception_in_a_step_over_ptys():
    outcome, marks, sink, motor, _ = run_on_ptys(RIG, fail_in_step=0)
    assert outcome.status == "failed" and "ValueError" in outcome.reason, outcome.reason
    assert_stopped_between(motor, marks["raised_at"], marks["received_by"])


@pytest.mark.timeout(120)
def test_tachometer_unplugged_over_ptys():
    # the tachometer's pty hangs up while the rotor holds its speed: real I/O errors
    pulled = {}

    def unplug(hosts, clock):
        pulled["t"] = clock.now()
        hosts["rotor_tach"].unplug()

    outcome, marks, sink, motor, hosts = run_on_ptys(RIG, on_settled=unplug, hold_s=30.0)
    assert outcome.status == "failed", (outcome.status, outcome.reason)
    interlock = sink.of_type("interlock")
    assert interlock and "rotor_tach" in interlock[0]["reason"], interlock
    assert_stopped_between(motor, pulled["t"], marks["received_by"])


@pytest.mark.timeout(120)
def test_sigint_over_ptys():
    outcome, marks, sink, motor, _ = run_on_ptys(RIG, sigint_in_step=0)
    assert outcome.status == "interrupted", outcome.reason
    assert_stopped_between(motor, marks["signalled_at"], marks["received_by"])


@pytest.mark.timeout(120)
def test_over_speed_over_ptys():
    # feed-forward calibrated for half the real full speed: the rotor overshoots to ~2x target
    text = RIG.replace("full_speed_rpm = 23873", "full_speed_rpm = 11000").replace(
        "max_speed_rpm = 24000", "max_speed_rpm = 12000")
    outcome, marks, sink, motor, _ = run_on_ptys(text, speed_rpm=11500.0, hold_s=6.0)
    assert outcome.status == "failed", (outcome.status, outcome.reason)
    interlock = sink.of_type("interlock")
    assert interlock and interlock[0]["reason"].startswith("over-speed"), interlock
    assert_stopped_between(motor, 0.0, marks["received_by"])
    assert interlock[0]["t"] <= marks["returned"]


@pytest.mark.timeout(120)
def test_controller_error_over_ptys():
    # the controller resets while the rotor holds its speed: it re-arms safe start, an error flag
    reset = {}

    def reset_controller(hosts, clock):
        emulator = hosts["rotor_motor"].emulator
        reset["t"] = clock.now()
        emulator.faults["reset_at"] = emulator.since_open(reset["t"])

    outcome, marks, sink, motor, _ = run_on_ptys(RIG, on_settled=reset_controller, hold_s=30.0)
    assert outcome.status == "failed", (outcome.status, outcome.reason)
    interlock = sink.of_type("interlock")
    assert interlock and "reports errors" in interlock[0]["reason"], interlock
    assert_stopped_between(motor, reset["t"], marks["received_by"])
