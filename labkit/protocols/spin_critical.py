"""``spin-critical``: rotor speed and floator spin at the moment the bound state breaks (Fig. 6.18).

Procedure of the paper (Sec. 6.5): start at the lowest rotor speed that traps the floator,
raise the speed by ``step_pct`` (10 %) per run. At each speed, for each trial: wait until a
floator is held (the balance carrying the rotator reads its weight; on a real rig the
operator places it), watch its spin tachometer while it spins up, and detect the drop by
a balance step (the weight disappears), the spin tachometer losing its target (silent or
below ``spin_loss_rpm``), or the operator pressing Enter. The pair (rotor speed, spin just
before the drop) is registered. Trials repeat until ``consistent_n`` successive spins agree
within ``consistency_pct`` (at most ``max_trials``).

Result rows: step, target_rpm, rotor_rad_s, rotor_rpm, spin_rad_s, spin_rpm, k (= v/w - 1,
Eq. 6.37), consistent, trials [{rotor_rad_s, spin_rad_s, cause, hold_s}], no_drop,
rotor_std_rad_s and spin_std_rad_s (the spread of the trials used: the report's error bars).
Quick fit: C of Eq. 6.37, ``-k w^2 = C (1 - w/3000)``, without steps marked inconsistent.
"""

from __future__ import annotations

import math
import statistics
from typing import Any

from labkit import documents as doc
from labkit.errors import LabkitError
from labkit.protocols.context import RunContext
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.drop_spin import drop_instant, fresh_samples, line_spacing, spin_at
from labkit.protocols.paper_figures import FIG_6_18, SPIN_CRITICAL_ROW
from labkit.protocols.params import MAX_PLAN_STEPS, ParamError, check_count
from labkit.protocols.quickfit import fit_spin_critical_c
from labkit.protocols.speed_sweep import reading_force_n
from labkit.rig import Rig
from labkit.units import force_n, gf_to_n, rad_s_to_rpm, rpm_to_rad_s


def point_from_trials(target_rpm: float, trials: list[dict[str, Any]], consistent: bool,
                      consistent_n: int) -> dict[str, Any]:
    """A step's row from its drops: the mean rotor speed and the median spin of the trials used
    (the last ``consistent_n`` when they agreed, else all), k of Eq. 6.37 and the spreads of the
    trials used (None with one trial). The run and the analysis-only replay share it."""
    row: dict[str, Any] = {"target_rpm": target_rpm, "trials": trials, "consistent": consistent,
                           "no_drop": not trials}
    if not trials:
        row.update(rotor_rad_s=None, rotor_rpm=None, spin_rad_s=None, spin_rpm=None, k=None,
                   rotor_std_rad_s=None, spin_std_rad_s=None)
        return row
    use = trials[-consistent_n:] if consistent else trials
    w = statistics.fmean(t["rotor_rad_s"] for t in use)
    v = statistics.median(t["spin_rad_s"] for t in use)
    spread = {f"{key[:-len('_rad_s')]}_std_rad_s": statistics.stdev(t[key] for t in use) if len(use) > 1
              else None for key in ("rotor_rad_s", "spin_rad_s")}
    row.update(rotor_rad_s=w, rotor_rpm=rad_s_to_rpm(w), spin_rad_s=v, spin_rpm=rad_s_to_rpm(v),
               k=v / w - 1.0, **spread)
    return row


def recorded_drops_point(step: int, events: list[dict[str, Any]],
                         params: dict[str, Any]) -> dict[str, Any] | None:
    """One point again from its recorded drops (the analysis-only rule: rotor speed and spin at
    each drop, as registered, through :meth:`SpinCritical.run_step`'s consistency rule)."""
    point = next((e for e in events if e["type"] == "point"), None)
    if point is None:
        return None
    trials = [{k: e[k] for k in ("rotor_rad_s", "spin_rad_s", "cause", "hold_s")}
              for e in events if e["type"] == "drop"]
    n = int(params["consistent_n"])
    consistent = False
    for i in range(len(trials)):
        recent = [t["spin_rad_s"] for t in trials[: i + 1][-n:]]
        spread = (max(recent) - min(recent)) / max(abs(statistics.fmean(recent)), 1e-9) * 100.0
        if len(recent) >= n and spread <= params["consistency_pct"]:
            consistent = True
            break
    return {"step": step, **point_from_trials(point["point"].get("target_rpm"), trials, consistent, n)}

class SpinCritical(ProtocolDef):
    name = "spin-critical"
    summary = "rotor speed and floator spin at the drop (Fig. 6.18, Eq. 6.37)"
    fit_model = "eq6.37"
    defaults: dict[str, Any] = {
        "start_rpm": 6000.0,        # lowest speed that traps the floator without spin
        "stop_rpm": 12000.0,        # last run at or below this
        "step_pct": 10.0,           # speed increase per run
        "max_trials": 4,
        "consistent_n": 2,
        "consistency_pct": 5.0,
        "place_timeout_s": 60.0,    # waiting for a floator to be held
        "trial_timeout_s": 90.0,    # no drop within this: register "no drop" and go on
        "held_fraction": 0.5,       # balance above this fraction of the floator weight = held
        "spin_loss_rpm": 60.0,      # spin tach below this (or silent) = target lost
        "floator_mass_g": 0.0,      # 0: bodies.floator.mass from the rig file
        "w_ref_rad_s": 3000.0,      # Eq. 6.37's reference speed
    }
    needs = (("rotor_motor", "motor"), ("rotor_tach", "tachometer"), ("floator_tach", "tachometer"),
             ("balance", "balance"))
    row = SPIN_CRITICAL_ROW
    hints = FIG_6_18   # the paper's figure and fits (labkit/protocols/paper_figures.py)
    w_ref = 3000.0

    def plan(self, rig: Rig, params: dict[str, Any]) -> list[Step]:
        start, stop, pct = params["start_rpm"], params["stop_rpm"], params["step_pct"]
        if start <= 0 or stop < start:
            raise ParamError(f"spin-critical: need 0 < start_rpm <= stop_rpm, got {start:g}, {stop:g}")
        if pct <= 0:
            raise ParamError("--set step_pct: must be > 0")
        check_count("step_pct", math.log(stop / start) / math.log1p(pct / 100.0) + 1, "steps", MAX_PLAN_STEPS)
        if params["max_trials"] < 1 or params["consistent_n"] < 1:
            raise ParamError("--set max_trials/consistent_n: must be >= 1")
        mass = params["floator_mass_g"] * 1e-3
        floator = rig.bodies.get("floator")
        if mass <= 0 and (floator is None or not floator.mass_kg):
            raise ParamError(f"spin-critical needs the floator's mass: bodies.floator.mass_g in {rig.path} "
                             "or --set floator_mass_g=...")
        self.w_ref = float(params["w_ref_rad_s"])
        steps: list[Step] = []
        rpm = float(start)
        while rpm <= stop * (1 + 1e-9):
            est = params["max_trials"] * 20.0
            steps.append(Step(len(steps), f"{rpm:.0f} RPM", {"rotor": rpm_to_rad_s(rpm)},
                              {"target_rpm": rpm}, est_duration_s=est))
            rpm *= 1 + pct / 100.0
        return steps

    def _weight_n(self, ctx: RunContext) -> float:
        grams = ctx.params["floator_mass_g"]
        if grams > 0:
            return gf_to_n(grams)
        mass_kg = ctx.rig.bodies["floator"].mass_kg
        if mass_kg is None:  # plan() refuses a rig without it: not reached
            raise ParamError(f"spin-critical needs the floator's mass: bodies.floator.mass_g in "
                             f"{ctx.rig.path} or --set floator_mass_g=...")
        return force_n(mass_kg, "kg")

    def setup(self, ctx: RunContext) -> None:
        balance = ctx.balance("balance")
        before = balance.read_stable()
        ctx.emit(doc.Zeroed(t=ctx.now(), device="balance", value=before.value, unit=before.unit))
        balance.zero()

    def _wait_held(self, ctx: RunContext, threshold: float, after_drop: bool) -> None:
        """Wait for a newly held floator: after a drop, first for the balance to show it gone
        (a balance's filter can lag the step), then for it to read the weight again."""
        start = ctx.now()
        phases = [False, True] if after_drop else [True]
        for want_held in phases:
            while (reading_force_n(ctx.read("balance")) >= threshold) != want_held:
                if ctx.now() - start > ctx.params["place_timeout_s"]:
                    raise LabkitError(
                        f"no floator held within {ctx.params['place_timeout_s']:.0f} s at "
                        f"{rad_s_to_rpm(ctx.control.snapshots()['rotor'].target_rad_s):.0f} RPM "
                        "(is start_rpm high enough to trap it?)")
                ctx.sleep(ctx.control.period_s)

    def _trial(self, ctx: RunContext, threshold: float, after_drop: bool) -> dict[str, Any] | None:
        """Watch one held floator until it drops; None if it never does."""
        p = ctx.params
        self._wait_held(ctx, threshold, after_drop)
        ctx.discard_operator_signals()   # only a key pressed while watching this floator counts
        held_at = last_held = ctx.now()
        loss = rpm_to_rad_s(p["spin_loss_rpm"])
        spin_seen = False
        while True:
            cause = None
            reading = ctx.read("balance")
            if reading_force_n(reading) >= threshold:
                last_held = reading.t
            else:
                cause = "balance"
            spin = ctx.tachometer("floator_tach").latest()
            if spin is not None and spin.t > held_at and spin.value > loss:
                spin_seen = True
            if cause is None and spin_seen:
                silent = spin is None or ctx.now() - spin.t > ctx.rig.control.tach_timeout_s
                if spin is None or silent or spin.value < loss:
                    cause = "spin_loss"
            if cause is None and ctx.operator_signalled():
                cause = "key"
            if cause is not None:
                gone_t = reading.t if cause == "balance" else (ctx.now() if cause == "key" else None)
                return self._pair(ctx, held_at, last_held, gone_t, loss, cause)
            if ctx.now() - held_at > p["trial_timeout_s"]:
                return None
            ctx.sleep(ctx.control.period_s)

    def _pair(self, ctx: RunContext, held_at: float, last_held: float, gone_t: float | None,
              loss: float, cause: str) -> dict[str, Any] | None:
        """The registered (rotor speed, spin at the drop) of one trial; None without readings.

        The spin is extrapolated to the drop instant from the window-mean tachometer lines
        (:mod:`labkit.protocols.drop_spin`), not the last line, which lags a spinning-up
        floator and biased Eq. 6.37's C high by 1-1.5 %."""
        spins = fresh_samples([(r.t, r.value) for r in ctx.tach_readings("floator_tach", held_at)
                               if r.t <= ctx.now()], loss)
        rotor = [r.value for r in ctx.tach_readings("rotor_tach", held_at) if r.t <= last_held]
        if not spins or not rotor:
            return None
        spacing = line_spacing([t for t, _ in spins])
        t_drop = drop_instant(last_held, gone_t, spins[-1][0], spacing)
        spins = [s for s in spins if s[0] <= t_drop + spacing]
        return {"rotor_rad_s": statistics.fmean(rotor), "spin_rad_s": spin_at(spins, t_drop),
                "cause": cause, "hold_s": t_drop - held_at}

    def run_step(self, ctx: RunContext, step: Step) -> dict[str, Any]:
        p = ctx.params
        ctx.set(rotor=step.targets_rad_s["rotor"])
        ctx.settle()
        threshold = p["held_fraction"] * self._weight_n(ctx)
        trials: list[dict[str, Any]] = []
        consistent = False
        for trial_no in range(int(p["max_trials"])):
            ctx.checkpoint()
            trial = self._trial(ctx, threshold, after_drop=trial_no > 0)
            if trial is None:
                break
            trials.append(trial)
            ctx.emit(doc.Drop(t=ctx.now(), index=step.index, trial=trial_no, **trial))
            recent = [t["spin_rad_s"] for t in trials[-int(p["consistent_n"]):]]
            if len(recent) >= p["consistent_n"]:
                spread = (max(recent) - min(recent)) / max(abs(statistics.fmean(recent)), 1e-9)
                if spread * 100.0 <= p["consistency_pct"]:
                    consistent = True
                    break
        return point_from_trials(step.data["target_rpm"], trials, consistent, int(p["consistent_n"]))

    def reanalyse_step(self, run: Any, step: int, events: list[dict[str, Any]]) -> dict[str, Any] | None:
        return recorded_drops_point(step, events, run.params)

    def fit(self, points: list[dict[str, Any]]) -> dict[str, Any]:
        """Eq. 6.37's C from the steps with a drop; a step whose trials did not agree
        (``consistent`` false) is left out while consistent ones remain, and named in
        ``left_out`` (``labkit fit`` and the live view leave it out too)."""
        measured = [pt for pt in points
                    if pt.get("rotor_rad_s") is not None and math.isfinite(pt["rotor_rad_s"])]
        agreed = [pt for pt in measured if pt.get("consistent") is not False]
        use = agreed or measured
        fit = fit_spin_critical_c([pt["rotor_rad_s"] for pt in use], [pt["spin_rad_s"] for pt in use],
                                  self.w_ref)
        left_out = [pt.get("step") for pt in measured if pt not in use]
        return {**fit, "left_out_steps": left_out} if left_out else fit
