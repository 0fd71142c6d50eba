"""Exit paths over real pseudo-terminals: emulators served by PtyHost, drivers on /dev/pts/N,
a real clock and the control loop in its own thread (the closest thing to hardware in CI).

Timing bounds are a control period plus scheduling slack for a loaded CI machine; the exact
"within one period" bounds are checked on the virtual clock in test_interlocks.py and
tests/protocols/test_runner_safety.py.
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

RIG = (Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml").read_text().replace(
    "settle_hold_s = 1.0", "settle_hold_s = 0.2")
SLACK = 0.05 + 0.25  # one control period + scheduling on a shared 2-core CI box


def run_on_ptys(rig_text, **overrides):
    rig = parse_rig(rig_text, "pty-rig.toml")
    clock = RealClock()
    hosts = {role: PtyHost(build_emulator(dev.port), clock=clock) for role, dev in rig.devices.items()}
    proto = Hold()
    sink = ListSink()
    params = resolve_params(proto.defaults, {"speed_rpm": 5000.0, "hold_s": 0.4, "steps": 1, **overrides})
    try:
        with use_clock(clock):
            runner = Runner(proto, rig, params, clock=clock, sinks=[sink],
                            port_override=lambda dev: hosts[dev.role].path)
            outcome = runner.run()
    finally:
        for host in hosts.values():
            host.close()
    return outcome, proto.marks, sink, shared_plant("model-fig525").motor("rotor"), hosts


@pytest.mark.timeout(60)
def test_normal_end_over_ptys():
    outcome, marks, sink, motor, hosts = run_on_ptys(RIG)
    assert outcome.status == "completed", outcome.reason
    assert all(h.path.startswith("/dev/pts/") for h in hosts.values())
    zeroed = motor.zeroed_since(marks["end_0"])
    assert zeroed is not None and zeroed - marks["end_0"] <= SLACK


@pytest.mark.timeout(60)
def test_exception_in_a_step_over_ptys():
    outcome, marks, sink, motor, _ = run_on_ptys(RIG, fail_in_step=0)
    assert outcome.status == "failed" and "ValueError" in outcome.reason
    zeroed = motor.zeroed_since(marks["raised_at"])
    assert zeroed is not None and zeroed - marks["raised_at"] <= SLACK


@pytest.mark.timeout(60)
def test_tachometer_unplugged_over_ptys():
    # the pty of the tachometer disappears 2 s after open (mid-hold): real I/O errors
    text = RIG.replace("role=rotor_tach&", "role=rotor_tach&faults=disconnect_at:2&")
    outcome, marks, sink, motor, hosts = run_on_ptys(text, hold_s=6.0)
    assert outcome.status == "failed"
    interlock = sink.of_type("interlock")
    assert interlock and "rotor_tach" in interlock[0]["reason"]
    zeroed = motor.zeroed_since(interlock[0]["t"] - SLACK)
    assert zeroed is not None and abs(zeroed - interlock[0]["t"]) <= SLACK
    assert motor.duty == 0.0


@pytest.mark.timeout(60)
def test_sigint_over_ptys():
    outcome, marks, sink, motor, _ = run_on_ptys(RIG, sigint_in_step=0)
    assert outcome.status == "interrupted"
    zeroed = motor.zeroed_since(marks["signalled_at"])
    assert zeroed is not None and zeroed - marks["signalled_at"] <= SLACK


@pytest.mark.timeout(60)
def test_over_speed_over_ptys():
    # feed-forward calibrated for half the real full speed: the rotor overshoots to ~2x target
    text = RIG.replace("full_speed_rpm = 23873", "full_speed_rpm = 11000").replace(
        "max_speed_rpm = 24000", "max_speed_rpm = 12000")
    outcome, marks, sink, motor, _ = run_on_ptys(text, speed_rpm=11500.0, hold_s=6.0)
    assert outcome.status == "failed"
    interlock = sink.of_type("interlock")
    assert interlock and interlock[0]["reason"].startswith("over-speed")
    zeroed = motor.zeroed_since(interlock[0]["t"] - SLACK)
    assert zeroed is not None and abs(zeroed - interlock[0]["t"]) <= SLACK


@pytest.mark.timeout(60)
def test_controller_error_over_ptys():
    # the controller resets 1.5 s after open (mid-run): it re-arms safe start, an error flag
    text = RIG.replace("role=rotor_motor", "role=rotor_motor&faults=reset_at:1.5")
    outcome, marks, sink, motor, _ = run_on_ptys(text, hold_s=6.0)
    assert outcome.status == "failed"
    interlock = sink.of_type("interlock")
    assert interlock and "reports errors" in interlock[0]["reason"], interlock
    zeroed = motor.zeroed_since(interlock[0]["t"] - SLACK)
    assert zeroed is not None and abs(zeroed - interlock[0]["t"]) <= SLACK
    assert motor.duty == 0.0
