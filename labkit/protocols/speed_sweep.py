"""``speed-sweep``: PFR force on a balance against rotor speed (the paper's Fig. 5.25).

For each planned speed (a range or list, optionally up then down for hysteresis, repeated)
the step: reads the balance at rest (rotor stopped), ramps to the speed, settles, averages
the balance for ``record_s``, stops the rotor and reads the balance at rest again. The
force is the mean at speed minus the rest reading interpolated linearly in time between
the two rest readings (drift correction), with its standard error. With
``zero=start`` the rest readings are skipped and the balance is only zeroed once: the drift
is then not measured (``drift_g`` null) and every point says so in its ``warnings``.

Result rows (``points`` of results.json): step, direction, repeat, target_rpm,
speed_rad_s, speed_rpm, speed_std_rpm, force_n, force_g, force_stderr_n, force_stderr_g, n,
settle_time_s, drift_n (the zero subtracted, N; 0 with ``zero=start``), drift_g (the same in
grams, null when not measured), unstable, and ``warnings`` (empty when none): the zero drifted
by more than ``drift_warn`` of the force, or was not measured. Quick fit: y = a x^b (x in RPM,
y in grams force).
"""

from __future__ import annotations

import math
import statistics
from typing import Any

from labkit import documents as doc
from labkit.errors import LabkitError
from labkit.protocols.context import RunContext
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.paper_figures import FIG_5_25, SPEED_SWEEP_ROW
from labkit.protocols.params import ParamError
from labkit.protocols.quickfit import quick_fit_power_law
from labkit.rig import Rig
from labkit.units import force_n, n_to_gf, rad_s_to_rpm, rpm_to_rad_s


def reading_force_n(reading: Any) -> float:
    """A balance reading as a force (N): kg readings are a mass under standard gravity
    (:func:`labkit.units.force_n`)."""
    try:
        return force_n(reading.value, reading.unit)
    except ValueError as exc:
        raise LabkitError(f"{reading.device or 'balance'}: {exc}") from None


def mean_stderr(values: list[float]) -> tuple[float, float]:
    """Mean and its standard error; LabkitError for a non-finite value (never a NaN point)."""
    if not all(math.isfinite(v) for v in values):
        raise LabkitError(f"balance: {sum(1 for v in values if not math.isfinite(v))} of {len(values)} "
                          "readings are not numbers; no force can be averaged")
    mean = statistics.fmean(values)
    if len(values) < 2:
        return mean, math.nan
    return mean, statistics.stdev(values) / math.sqrt(len(values))


def finite_std(values: list[float]) -> float:
    """Sample standard deviation of the finite values (NaN with fewer than two)."""
    finite = [v for v in values if math.isfinite(v)]
    return statistics.stdev(finite) if len(finite) > 1 else math.nan


def check_overload(ctx: RunContext, role: str, readings: list[Any], speed_rad_s: float) -> None:
    """Raise one line naming the balance, the speed and its capacity when any reading was an
    overload (value NaN, ``overload=True``): the run ends, motors to zero, and that is its
    stop reason. An overloaded reading has no value, so no force may be averaged from it."""
    over = [r for r in readings if getattr(r, "overload", False)]
    if not over:
        return
    device = ctx.devices[role]
    capacity = getattr(device, "capacity", None)
    unit = getattr(device, "unit", "") or ""
    capacity_text = (f"capacity {capacity:g} {unit}".strip() if isinstance(capacity, int | float)
                     else "capacity of the balance exceeded; `labkit probe balance` shows its rating")
    speed = "at rest" if speed_rad_s < 1.0 else f"at {rad_s_to_rpm(speed_rad_s):.0f} RPM"
    raise LabkitError(f"{role}: balance overload {speed} ({capacity_text}; {len(over)} of {len(readings)} "
                      "readings): lower the speeds or use a balance with a larger range; motors at zero")


def drift_warnings(force_g: float, drift_g: float, rests_g: tuple[float, float] | None,
                   fraction: float) -> list[str]:
    """What a point says about its balance zero: drifted by more than ``fraction`` of the force
    (subtracted, but the force rests on the drift being linear in time between the two rest
    readings), or not measured at all (``rests_g`` None: ``zero=start``)."""
    if rests_g is None:
        return ["balance drift not measured (zero=start: zeroed once at the start, no rest readings); "
                "the force includes any drift of the zero since then; zero=each measures it"]
    if not (math.isfinite(force_g) and abs(drift_g) > fraction * abs(force_g)):
        return []
    share = abs(drift_g) / abs(force_g) if force_g else math.inf
    return [f"balance zero drifted {drift_g:+.3f} g by this point ({share:.0%} of the force {force_g:.3f} g, "
            f"above drift_warn {fraction:.0%}); subtracted as the rest readings before ({rests_g[0]:+.3f} g) "
            f"and after ({rests_g[1]:+.3f} g) the step, linear in time"]


def recorded_window_point(step: int, events: list[dict[str, Any]], readings: dict[str, list[Any]],
                          params: dict[str, Any]) -> dict[str, Any] | None:
    """One point again from its recorded window (the analysis-only rule, :meth:`SpeedSweep.run_step`'s
    averages over the ``settled`` event to the rotor's stop) and the re-parsed ``readings``."""
    settled = next((e for e in events if e["type"] == "settled"), None)
    point = next((e for e in events if e["type"] == "point"), None)
    targets = [e for e in events if e["type"] == "setpoint"]
    if settled is None or point is None:
        return None
    t_start = settled["t"]
    stop = next((e["t"] for e in targets if e["t"] > t_start and e["target_rad_s"] == 0.0), point["t"])
    t_end = min(stop, point["t"])
    balance = readings["balance"]
    at_speed = [r for r in balance if t_start < r.t <= t_end]
    speeds = [r.value for r in readings["rotor_tach"] if t_start < r.t <= t_end]
    drift, rests_g = 0.0, None
    if params["zero"] == "each":
        go = next((e["t"] for e in targets if e["target_rad_s"] > 0), t_start)
        before = [r for r in balance if r.t <= go and r.t >= events[0]["t"]]
        after = [r for r in balance if t_end < r.t <= point["t"]]
        if before and after:
            r0, r1 = before[-1], after[-1]
            t_mid = 0.5 * (at_speed[0].t + at_speed[-1].t) if at_speed else t_start
            frac = (t_mid - r0.t) / (r1.t - r0.t) if r1.t > r0.t else 0.5
            drift = reading_force_n(r0) + frac * (reading_force_n(r1) - reading_force_n(r0))
            rests_g = (n_to_gf(reading_force_n(r0)), n_to_gf(reading_force_n(r1)))
    force, stderr = mean_stderr([reading_force_n(r) - drift for r in at_speed])
    finite = [v for v in speeds if math.isfinite(v)]
    speed = statistics.fmean(finite) if finite else math.nan
    data = point["point"]
    return {"step": step, "direction": data.get("direction"), "repeat": data.get("repeat"),
            "target_rpm": data.get("target_rpm"), "speed_rad_s": speed, "speed_rpm": rad_s_to_rpm(speed),
            "speed_std_rpm": rad_s_to_rpm(finite_std(speeds)), "force_n": force, "force_g": n_to_gf(force),
            "force_stderr_n": stderr, "force_stderr_g": n_to_gf(stderr), "n": len(at_speed),
            "settle_time_s": settled["settle_time_s"], "drift_n": drift,
            "drift_g": n_to_gf(drift) if rests_g else None,
            "unstable": sum(1 for r in at_speed if not r.stable),
            "warnings": drift_warnings(n_to_gf(force), n_to_gf(drift), rests_g,
                                       float(params.get("drift_warn", 0.05)))}

class SpeedSweep(ProtocolDef):
    name = "speed-sweep"
    summary = "PFR force vs rotor speed on a balance (Fig. 5.25)"
    fit_model = "power-law"
    defaults: dict[str, Any] = {
        "speeds_rpm": [6000.0 + 1000.0 * i for i in range(15)],  # 6000:20000:1000
        "up_down": False,        # also sweep back down (hysteresis)
        "repeats": 1,
        "record_s": 3.0,         # averaging time at each speed
        "min_samples": 5,
        "zero": "each",          # "each": rest readings before/after every step; "start": zero once
        "drift_warn": 0.05,      # a point warns when the zero drifted by more than this fraction of its force
        "settle_timeout_s": 0.0,  # 0: the rig's control.settle_timeout
    }
    needs = (("rotor_motor", "motor"), ("rotor_tach", "tachometer"), ("balance", "balance"))
    row = SPEED_SWEEP_ROW
    hints = FIG_5_25   # the paper's figure and fits (labkit/protocols/paper_figures.py)

    def plan(self, rig: Rig, params: dict[str, Any]) -> list[Step]:
        speeds = list(params["speeds_rpm"])
        if not speeds:
            raise ParamError("speed-sweep: speeds_rpm is empty")
        if params["zero"] not in ("each", "start"):
            raise ParamError(f"--set zero: must be each or start, got {params['zero']!r}")
        if not 0 < float(params["drift_warn"]) < 10:
            raise ParamError("--set drift_warn: a fraction of the force (0.05 = 5 %), "
                             f"got {params['drift_warn']!r}")
        if params["repeats"] < 1:
            raise ParamError("--set repeats: must be >= 1")
        legs = [("up", speeds)]
        if params["up_down"]:
            legs.append(("down", list(reversed(speeds))[1:]))
        from labkit.protocols.params import MAX_PLAN_STEPS, check_count

        n_steps = sum(len(leg) for _, leg in legs) * int(params["repeats"])
        check_count("repeats", n_steps, "steps", MAX_PLAN_STEPS)
        steps: list[Step] = []
        ramp = rig.limits.max_ramp_rad_s2
        for repeat in range(int(params["repeats"])):
            for direction, leg in legs:
                for rpm in leg:
                    target = rpm_to_rad_s(rpm)
                    est = 2 * target / ramp + rig.control.settle_hold_s + float(params["record_s"]) + 3.0
                    steps.append(Step(len(steps), f"{direction} {rpm:.0f} RPM (run {repeat + 1})",
                                      {"rotor": target},
                                      {"direction": direction, "repeat": repeat, "target_rpm": rpm},
                                      est_duration_s=est))
        return steps

    def setup(self, ctx: RunContext) -> None:
        balance = ctx.balance("balance")
        before = balance.read_stable()
        ctx.emit(doc.Zeroed(t=ctx.now(), device="balance", value=before.value, unit=before.unit))
        balance.zero()

    def _rest(self, ctx: RunContext) -> tuple[float, float]:
        ctx.wait_stopped("rotor")
        reading = ctx.balance("balance").read_stable()
        ctx.emit_reading("balance", reading)
        check_overload(ctx, "balance", [reading], 0.0)
        return reading.t, reading_force_n(reading)

    def run_step(self, ctx: RunContext, step: Step) -> dict[str, Any]:
        p = ctx.params
        each = p["zero"] == "each"
        rest0 = self._rest(ctx) if each else None
        ctx.set(rotor=step.targets_rad_s["rotor"])
        settle_time = ctx.settle(p["settle_timeout_s"] or None)
        t_start = ctx.now()
        readings = ctx.record("balance", float(p["record_s"]), int(p["min_samples"]))
        t_end = ctx.now()
        speeds = [r.value for r in ctx.tach_readings("rotor_tach", t_start) if r.t <= t_end]
        finite_speeds = [v for v in speeds if math.isfinite(v)]
        check_overload(ctx, "balance", readings,
                       statistics.fmean(finite_speeds) if finite_speeds else step.targets_rad_s["rotor"])
        rest1 = self._rest(ctx) if each else None
        forces = [reading_force_n(r) for r in readings]
        drift = 0.0
        if rest0 and rest1:
            t_mid = 0.5 * (t_start + t_end)
            frac = (t_mid - rest0[0]) / (rest1[0] - rest0[0]) if rest1[0] > rest0[0] else 0.5
            drift = rest0[1] + frac * (rest1[1] - rest0[1])
        force, stderr = mean_stderr([f - drift for f in forces])
        speed = statistics.fmean(finite_speeds) if finite_speeds else math.nan
        speed_std = finite_std(speeds)
        rests_g = (n_to_gf(rest0[1]), n_to_gf(rest1[1])) if rest0 and rest1 else None
        warnings = drift_warnings(n_to_gf(force), n_to_gf(drift), rests_g, float(p["drift_warn"]))
        return {
            "direction": step.data["direction"], "repeat": step.data["repeat"],
            "target_rpm": step.data["target_rpm"],
            "speed_rad_s": speed, "speed_rpm": rad_s_to_rpm(speed), "speed_std_rpm": rad_s_to_rpm(speed_std),
            "force_n": force, "force_g": n_to_gf(force),
            "force_stderr_n": stderr, "force_stderr_g": n_to_gf(stderr),
            "n": len(forces), "settle_time_s": settle_time, "drift_n": drift,
            "drift_g": n_to_gf(drift) if rests_g else None,
            "unstable": sum(1 for r in readings if not r.stable),
            "warnings": warnings,
        }

    def reanalyse_step(self, run: Any, step: int, events: list[dict[str, Any]]) -> dict[str, Any] | None:
        return recorded_window_point(step, events, run.readings, run.params)

    def fit(self, points: list[dict[str, Any]]) -> dict[str, Any]:
        usable = [pt for pt in points
                  if pt.get("speed_rpm") is not None and pt.get("force_g") is not None and pt["force_g"] > 0]
        sigma = [pt["force_stderr_g"] if pt.get("force_stderr_g") is not None else math.nan for pt in usable]
        return quick_fit_power_law([pt["speed_rpm"] for pt in usable], [pt["force_g"] for pt in usable],
                                   sigma)
