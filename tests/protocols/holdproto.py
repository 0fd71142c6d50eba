"""A tiny protocol for safety tests: hold one speed, optionally fail or signal mid-step."""

import os
import signal

from labkit.protocols.definition import ProtocolDef, Step
from labkit.units import rpm_to_rad_s


class Hold(ProtocolDef):
    name = "hold"
    defaults = {"speed_rpm": 10000.0, "hold_s": 2.0, "steps": 2, "fail_in_step": -1, "sigint_in_step": -1,
                "sigints": 1}
    needs = (("rotor_motor", "motor"), ("rotor_tach", "tachometer"))

    def __init__(self):
        self.marks = {}

    def plan(self, rig, params):
        target = rpm_to_rad_s(params["speed_rpm"])
        return [Step(i, f"hold {i}", {"rotor": target}) for i in range(params["steps"])]

    def run_step(self, ctx, step):
        ctx.set(rotor=step.targets_rad_s["rotor"])
        ctx.settle()
        ctx.sleep(ctx.params["hold_s"] / 2)
        if step.index == ctx.params["fail_in_step"]:
            self.marks["raised_at"] = ctx.now()
            raise ValueError("bad arithmetic in a step")
        if step.index == ctx.params["sigint_in_step"]:
            self.marks["signalled_at"] = ctx.now()
            for _ in range(ctx.params["sigints"]):
                os.kill(os.getpid(), signal.SIGINT)
        ctx.sleep(ctx.params["hold_s"] / 2)
        self.marks[f"end_{step.index}"] = ctx.now()
        tach = ctx.tach_readings("rotor_tach", ctx.now() - 0.5)
        return {"speed_rad_s": tach[-1].value}
