"""Every exit path of a run ends with the motor commanded to zero (emulated rig, virtual clock)."""

from pathlib import Path

import pytest

from labkit.emulators.plant import shared_plant
from labkit.io.clock import VirtualClock, use_clock
from labkit.protocols import ListSink, Runner
from labkit.protocols.params import resolve_params
from labkit.rig import load_rig

from .holdproto import Hold

RIG = Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml"
PERIOD = 0.05


def run_hold(**overrides):
    proto = Hold()
    rig = load_rig(RIG)
    clock = VirtualClock()
    sink = ListSink()
    with use_clock(clock):
        runner = Runner(proto, rig, resolve_params(proto.defaults, overrides), clock=clock, sinks=[sink])
        outcome = runner.run()
    return outcome, proto.marks, sink, shared_plant("model-fig525").motor("rotor")


def test_normal_end_zeroes_the_motor_at_once():
    outcome, marks, sink, motor = run_hold()
    assert outcome.status == "completed"
    assert len(outcome.results["points"]) == 2
    zeroed = motor.zeroed_since(marks["end_1"])
    assert zeroed is not None and zeroed - marks["end_1"] <= PERIOD
    assert sink.of_type("stop")[0]["status"] == "completed"


def test_exception_in_a_step_zeroes_the_motor_and_keeps_finished_points():
    outcome, marks, sink, motor = run_hold(fail_in_step=1)
    assert outcome.status == "failed"
    assert "ValueError: bad arithmetic in a step" in outcome.reason
    zeroed = motor.zeroed_since(marks["raised_at"])
    assert zeroed is not None and zeroed - marks["raised_at"] <= PERIOD
    assert [p["step"] for p in outcome.results["points"]] == [0]
    assert sink.of_type("fault")[0]["reason"] == outcome.reason


def test_first_sigint_goes_safe_within_a_period_and_stops_at_the_checkpoint():
    outcome, marks, sink, motor = run_hold(sigint_in_step=0)
    assert outcome.status == "interrupted"
    zeroed = motor.zeroed_since(marks["signalled_at"])
    assert zeroed is not None and zeroed - marks["signalled_at"] <= PERIOD + 1e-9
    assert outcome.results["points"] == []  # the interrupted step is not half-recorded
    assert [e["count"] for e in sink.of_type("stop_request")] == [1]


def test_second_sigint_forces_the_safe_state_now():
    outcome, marks, sink, motor = run_hold(sigint_in_step=0, sigints=2)
    assert outcome.status == "interrupted"
    assert "twice" in outcome.reason
    assert motor.zeroed_since(marks["signalled_at"]) == pytest.approx(marks["signalled_at"])
    assert sink.of_type("interlock")[0]["reason"] == "Ctrl-C pressed twice"


def test_sigint_handler_is_restored_after_the_run():
    import signal

    before = signal.getsignal(signal.SIGINT)
    run_hold(steps=1)
    assert signal.getsignal(signal.SIGINT) is before
