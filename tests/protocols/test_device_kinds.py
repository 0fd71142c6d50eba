"""The device kinds as typed protocols (labkit.devices.kinds): every built-in driver of a kind
satisfies its kind's protocol, a motor or a tachometer is no balance, a motor no tachometer and
nothing but a motor controller a motor, so ``RunContext.balance`` / ``.tachometer`` / ``.motor``
/ ``.camera`` refuse them (a streaming balance also offers its readings as a tachometer does:
structural, as intended). The speed loop takes its motor and tachometer through the kinds."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.control.loop import build_speed_control
from labkit.devices.kinds import BalanceKind, CameraKind, MotorKind, TachometerKind
from labkit.emulators.plant import reset_plants
from labkit.errors import LabkitError
from labkit.io.clock import VirtualClock, use_clock
from labkit.protocols import ListSink, Runner
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.params import resolve_params
from labkit.rig import load_rig, open_rig
from labkit.units import rpm_to_rad_s

REPO = Path(__file__).resolve().parents[2]
KINDS = {"balance": BalanceKind, "tachometer": TachometerKind, "motor": MotorKind, "camera": CameraKind}


@pytest.mark.parametrize("rig_name", ["emulated-fig525", "emulated-fig618", "emulated-camera"])
def test_each_driver_satisfies_its_kinds_protocol(rig_name):
    rig = load_rig(REPO / "rigs" / f"{rig_name}.toml")
    clock = VirtualClock()
    seen = set()
    with use_clock(clock), open_rig(rig, clock) as opened:
        for role, driver in opened.drivers.items():
            kind = rig.devices[role].kind
            matches = {k for k, proto in KINDS.items() if isinstance(driver, proto)}
            if kind in KINDS:
                assert kind in matches, (role, kind, matches)
            if kind in ("tachometer", "motor", "strobe"):
                assert "balance" not in matches and "camera" not in matches, (role, kind, matches)
            if kind == "motor":
                assert matches == {"motor"}, (role, matches)
            else:
                assert "motor" not in matches, (role, kind, matches)
            seen.add(kind)
    assert seen & set(KINDS)


class MotorStatusHold(ProtocolDef):
    """Hold one speed; read the motor controller's status through ``ctx.motor``."""

    name = "motor-status-hold"
    defaults = {"speed_rpm": 6000.0}
    needs = (("rotor_motor", "motor"), ("rotor_tach", "tachometer"))

    def __init__(self) -> None:
        self.seen: dict = {}

    def plan(self, rig, params):
        return [Step(0, "hold", {"rotor": rpm_to_rad_s(params["speed_rpm"])})]

    def run_step(self, ctx, step):
        ctx.set(rotor=step.targets_rad_s["rotor"])
        ctx.settle()
        status = ctx.motor("rotor_motor").status()
        self.seen["duty"], self.seen["errors"] = status.duty, status.errors
        for role in ("rotor_tach", "balance"):
            try:
                ctx.motor(role)
            except LabkitError as exc:
                self.seen[role] = str(exc)
        return {"duty": status.duty}


def test_a_step_reads_the_motor_controller_through_ctx_motor_and_nothing_else_passes():
    reset_plants()
    proto = MotorStatusHold()
    clock = VirtualClock()
    with use_clock(clock):
        rig = load_rig(REPO / "rigs" / "emulated-fig525.toml")
        params = resolve_params(proto.defaults, {})
        outcome = Runner(proto, rig, params, clock=clock, sinks=[ListSink()]).run()
    reset_plants()
    assert outcome.status == "completed", outcome.reason
    assert 0 < proto.seen["duty"] <= 1 and not proto.seen["errors"]
    for role in ("rotor_tach", "balance"):
        assert f"needs a motor controller called {role!r}; the rig has" in proto.seen[role]


def test_the_speed_loop_refuses_a_driver_of_the_wrong_kind_by_role():
    rig = load_rig(REPO / "rigs" / "emulated-fig525.toml")
    clock = VirtualClock()
    with use_clock(clock), open_rig(rig, clock) as opened:
        assert isinstance(build_speed_control(opened, clock).loops["rotor"].motor, MotorKind)
        right = opened.drivers["rotor_motor"]
        opened.drivers["rotor_motor"] = opened.drivers["balance"]  # a wrong driver under the motor's role
        try:
            wanted = (r"rotor_motor \(\w+\) cannot serve the speed loop as a motor controller: "
                      r"it needs enable, set_duty, stop and status")
            with pytest.raises(LabkitError, match=wanted):
                build_speed_control(opened, clock)
        finally:
            opened.drivers["rotor_motor"] = right


def test_the_type_checker_refuses_a_duty_commanded_from_a_step(tmp_path):
    # ctx.motor is typed as MotorStatusKind: a step reads the status; speeds go through ctx.set
    api = pytest.importorskip("mypy.api")
    step = tmp_path / "step.py"
    step.write_text("from labkit.protocols.context import RunContext\n\n\n"
                    "def step(ctx: RunContext) -> float:\n"
                    "    ctx.motor('rotor_motor').set_duty(1.0)\n"
                    "    return ctx.motor('rotor_motor').status().duty\n")
    out, _, status = api.run(["--follow-imports=silent", "--ignore-missing-imports",
                              "--cache-dir", str(REPO / ".mypy_cache"), str(step)])
    assert status == 1 and out.count("error:") == 1
    assert 'step.py:5: error: "MotorStatusKind" has no attribute "set_duty"' in out
