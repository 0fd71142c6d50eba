"""Exit paths inside one process on the virtual clock (exact bounds; the cross-process matrix
with `labkit emulate` and `labkit run` is in test_matrix.py).

SIGTERM, SIGHUP and SIGQUIT take the Ctrl-C path; NaN never reaches the wire; a STOP that
cannot be delivered is reported, not swallowed.
"""

from __future__ import annotations

import math
import os
import signal
from pathlib import Path

import pytest

from labkit.emulators.plant import reset_plants, shared_plant
from labkit.errors import SafetyError
from labkit.io.clock import VirtualClock, use_clock
from labkit.io.ports import open_port
from labkit.protocols import ListSink, Runner
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.params import resolve_params
from labkit.rig import load_rig, parse_rig
from labkit.units import rpm_to_rad_s

RIG = Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml"
PERIOD = 0.05


class SignalledHold(ProtocolDef):
    """Hold one speed; send ``signum`` to this process mid-step (``times`` times)."""

    name = "signalled-hold"
    defaults = {"speed_rpm": 8000.0, "signum": 0, "times": 1}
    needs = (("rotor_motor", "motor"), ("rotor_tach", "tachometer"))

    def __init__(self) -> None:
        self.marks: dict[str, float] = {}

    def plan(self, rig, params):
        return [Step(0, "hold", {"rotor": rpm_to_rad_s(params["speed_rpm"])})]

    def run_step(self, ctx, step):
        ctx.set(rotor=step.targets_rad_s["rotor"])
        ctx.settle()
        if ctx.params["signum"]:
            self.marks["signalled_at"] = ctx.now()
            for _ in range(ctx.params["times"]):
                os.kill(os.getpid(), ctx.params["signum"])
        ctx.sleep(1.0)
        return {"speed_rad_s": ctx.tach_readings("rotor_tach", ctx.now() - 0.5)[-1].value}


@pytest.fixture(autouse=True)
def fresh_plants():
    reset_plants()
    yield
    reset_plants()


def run_signalled(rig_text: str | None = None, kp: float | None = None, **overrides):
    proto = SignalledHold()
    rig = parse_rig(rig_text, "safety-rig.toml") if rig_text else load_rig(RIG)
    if kp is not None:  # past the rig file's own checks: what reaches the control loop
        object.__setattr__(rig.control, "kp", kp)
    clock = VirtualClock()
    sink = ListSink()
    with use_clock(clock):
        runner = Runner(proto, rig, resolve_params(proto.defaults, overrides), clock=clock, sinks=[sink])
        outcome = runner.run()
    return outcome, proto.marks, sink, shared_plant("model-fig525").motor("rotor")


@pytest.mark.parametrize("name", ["SIGTERM", "SIGHUP", "SIGQUIT"])
def test_stop_signals_take_the_ctrl_c_path(name):
    signum = int(getattr(signal, name))
    before = signal.getsignal(signum)
    outcome, marks, sink, motor = run_signalled(signum=signum, times=2)  # a repeat never escalates
    assert outcome.status == "interrupted"
    assert outcome.reason == f"stopped by {name} at a checkpoint; motors at zero"
    zeroed = motor.zeroed_since(marks["signalled_at"])
    assert zeroed is not None and zeroed - marks["signalled_at"] <= PERIOD + 1e-9
    assert [e["signal"] for e in sink.of_type("stop_request")] == [name]
    assert not sink.of_type("interlock")  # the first-Ctrl-C path, not the forced one
    assert signal.getsignal(signum) is before


def test_nan_gain_never_moves_the_motor():
    outcome, marks, sink, motor = run_signalled(kp=math.nan)
    assert outcome.status == "failed"
    assert "not a finite number" in outcome.reason and "kp" in outcome.reason
    assert sink.of_type("interlock")
    assert motor.duty == 0.0
    assert [duty for _, duty in motor.duty_changes if duty != 0.0] == []


@pytest.mark.parametrize("protocol,command", [("pololu_smc", "set_duty"), ("vesc", "SET_DUTY")])
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_duty_at_the_driver_edge_becomes_zero_and_an_error(protocol, command, bad):
    from labkit.devices.registry import driver_class

    clock = VirtualClock()
    with use_clock(clock):
        port = open_port(f"sim://{protocol}?plant=edge", clock=clock, baudrate=115200, timeout=0.2)
        motor = driver_class("motor", protocol)(port, clock, name="rotor_motor")
        motor.enable()
        motor.set_duty(0.3)
        clock.sleep(0.5)
        plant = shared_plant("edge").motor("rotor")
        assert plant.duty == pytest.approx(0.3, abs=0.01)
        with pytest.raises(SafetyError, match=f"rotor_motor: {command} .* not a finite number"):
            motor.set_duty(bad)
        assert plant.duty == 0.0
        motor.close()


def test_a_stop_that_cannot_be_delivered_is_reported_not_swallowed():
    # the controller's port disappears 2.5 s after open (mid-hold): no STOP can reach it
    text = RIG.read_text().replace("role=rotor_motor", "role=rotor_motor&faults=disconnect_at:2.5")
    outcome, marks, sink, motor = run_signalled(text)
    assert outcome.status == "failed"
    assert outcome.stop_failed and "port gone" in outcome.stop_failed["rotor_motor"]
    assert outcome.reason.startswith("could not stop rotor_motor: port gone")
    assert "cut the motor's power" in outcome.reason
    assert sink.of_type("stop_failed")[0]["devices"] == outcome.stop_failed
    assert "motors commanded to zero" not in outcome.reason.split("(")[0]
