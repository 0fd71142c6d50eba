"""Work-precision: error against run time for every integrator of :mod:`labkit.sim`.

Follows DiffEqDevTools / CyRK practice (docs/explanation/numerics-notes.md#work-precision-reports):

* a **cross-checked reference**: the default splitting at a large step count and scipy DOP853
  at a tight tolerance must agree (T8: to 1e-10) before any error is published; their
  disagreement is reported with every table;
* a **sweep** of steps per period (fixed-step splittings) or tolerances (scipy methods);
  each point is run once for its errors; its time is the run's wall time (compile excluded),
  the minimum over repeats when a run is short;
* **failures are shown, never dropped**: a run that fails (exception, NaN, blow-up, solver
  failure) is a point with NaN error and its status;
* the **observed order** of each fixed-step method, the **cost to reach** 1e-4 ... 1e-10
  (Pareto front, log-log interpolation) and the **speedup at equal error** against DOP853.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from labkit.numerics import metrics
from labkit.numerics.checks import NumericsError, check_horizon, check_rtol, check_steps
from labkit.sim import CompiledSystem, Scene, compile_scene, load_scene, simulate
from labkit.sim.integrators import SPLITTINGS
from labkit.sim.integrators.splitting import COMPOSITIONS
from labkit.sim.result import SimResult

TARGETS = (1e-4, 1e-6, 1e-8, 1e-10)
REFERENCE_AGREEMENT = 1e-10  # docs/explanation/numerics-notes.md#targets (T8)
REFERENCE_STEPS = 512
REFERENCE_RTOL = 1e-12
REPEAT_BELOW_S = 0.3  # runs shorter than this are repeated and the minimum kept
REPEATS = 4


@dataclass
class Ladder:
    """Settings to sweep per integrator: steps per period (splittings) or rtol (scipy)."""

    steps: dict[str, list[int]]
    rtols: dict[str, list[float]]

    @classmethod
    def quick(cls) -> Ladder:
        return cls(
            steps={"splitting4": [8, 16, 32, 64, 128, 256, 512], "strang": [64, 256, 1024, 4096]},
            rtols={"dop853": [1e-5, 1e-7, 1e-9, 1e-11, 1e-12]},
        )

    @classmethod
    def full(cls) -> Ladder:
        return cls(
            steps={
                "splitting4": [8, 16, 32, 64, 128, 256, 512],
                "yoshida4": [16, 32, 64, 128, 256],
                "yoshida6": [8, 16, 32, 64, 128],
                "strang": [64, 128, 256, 512, 1024, 2048, 4096],
            },
            rtols={
                "dop853": [1e-4, 1e-6, 1e-8, 1e-10, 1e-11, 1e-12],
                "radau": [1e-4, 1e-6],
                "lsoda": [1e-6, 1e-8],
            },
        )


@dataclass
class Point:
    """One run of the sweep (the JSON row of ``labkit bench sim``)."""

    scene: str
    integrator: str
    setting: str
    status: str
    error: float  # final stroboscopic state error (dimensionless, max norm)
    errors: dict
    invariant_drift: float
    wall_s: float
    n_rhs: int
    steps_per_period: int | None = None
    rtol: float | None = None
    message: str = ""

    def row(self) -> dict:
        """The row of the issue's JSON schema."""
        return {
            "id": self.scene,
            "integrator": self.integrator,
            "setting": self.setting,
            "error": _num(self.error),
            "invariant_drift": _num(self.invariant_drift),
            "wall_s": _num(self.wall_s),
            "n_rhs": self.n_rhs,
        }


@dataclass
class Reference:
    """The reference run and how well independent methods agree with it
    (docs/explanation/numerics-notes.md#targets, T8)."""

    result: SimResult
    other: SimResult
    agreement: float
    dop853: SimResult | None
    dop853_agreement: float
    cross_checked: bool
    description: str


@dataclass
class SceneReport:
    scene: str
    cycles: float
    reference: Reference
    points: list[Point]
    orders: dict[str, dict] = field(default_factory=dict)
    cost: dict[str, dict] = field(default_factory=dict)


def _num(x: float | None) -> float | None:
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _moments(scene: Scene) -> list:
    return [b.moment_Am2 for b in scene.bodies]


def _as_scene(scene: Scene | str) -> Scene:
    return scene if isinstance(scene, Scene) else load_scene(scene)


def timed_run(scene: Scene, system: CompiledSystem, cycles: float, integrator: str, **kw) -> SimResult:
    """One run for its errors; short runs are repeated and the fastest wall time kept."""

    def run() -> SimResult:
        return simulate(
            scene,
            cycles,
            integrator,
            system=system,
            drift_threshold=math.inf,
            rotation_threshold=math.inf,
            samples_per_period=1,
            **kw,
        )

    res = run()
    best = res.wall_s
    repeats = 0
    while best < REPEAT_BELOW_S and repeats < REPEATS:
        best = min(best, run().wall_s)
        repeats += 1
    res.wall_s = best
    return res


def reference(
    scene: Scene | str,
    cycles: float,
    steps: int = REFERENCE_STEPS,
    rtol: float = REFERENCE_RTOL,
    with_dop853: bool = True,
) -> Reference:
    """The reference: yoshida6 at ``steps`` per period, cross-checked against splitting4 at
    ``2 steps`` (another composition and order, another truncation error: they must agree to
    1e-10, T8) and, with ``with_dop853``, against scipy DOP853 at ``rtol`` (another state
    representation and method; its own error usually sets that agreement).

    Round-off in the step loop grows with steps x cycles (~1e-10 after 50 cycles of 2048
    steps), so long horizons cannot be cross-checked to 1e-10: the description says so.
    """
    scene = _as_scene(scene)
    system = compile_scene(scene)
    check_horizon(cycles, 1, len(scene.bodies))
    check_rtol(rtol)
    kw = {
        "samples_per_period": 1,
        "system": system,
        "drift_threshold": math.inf,
        "rotation_threshold": math.inf,
    }
    moments = _moments(scene)
    primary = simulate(scene, cycles, "yoshida6", steps_per_period=steps, **kw)
    other = simulate(scene, cycles, "splitting4", steps_per_period=2 * steps, **kw)
    agreement = metrics.state_errors(other, primary, system.length_scale, system.omega, moments).linf
    dop, dop_agreement = None, math.nan
    if with_dop853:
        dop = simulate(scene, cycles, "dop853", rtol=rtol, **kw)
        dop_agreement = metrics.state_errors(dop, primary, system.length_scale, system.omega, moments).linf
    ok = primary.status == "ok" and other.status == "ok" and agreement <= REFERENCE_AGREEMENT
    text = (
        f"yoshida6 N={steps} vs splitting4 N={2 * steps} over {cycles:g} cycles: agree to {agreement:.2g}"
        + ("" if ok else f" (> {REFERENCE_AGREEMENT:g}: NOT cross-checked)")
    )
    if dop is not None:
        text += f"; vs DOP853 rtol={rtol:g}: {dop_agreement:.2g}"
    return Reference(primary, other, agreement, dop, dop_agreement, ok, text)


def run_point(
    scene: Scene,
    system: CompiledSystem,
    ref: SimResult,
    cycles: float,
    integrator: str,
    steps: int | None = None,
    rtol: float | None = None,
) -> Point:
    """Run one setting; any failure becomes a point with NaN errors and its status."""
    setting = f"N={steps}" if steps is not None else f"rtol={rtol:g}"
    kw = {"steps_per_period": steps} if steps is not None else {"rtol": rtol}
    try:
        if steps is not None:
            check_steps(steps, system.omega, system.omega_max, COMPOSITIONS[SPLITTINGS[integrator]][1])
        res = timed_run(scene, system, cycles, integrator, **kw)
    except Exception as exc:  # noqa: BLE001 - a failing setting is a result to show
        return Point(
            scene.name,
            integrator,
            setting,
            "failed",
            math.nan,
            {},
            math.nan,
            math.nan,
            0,
            steps,
            rtol,
            f"{type(exc).__name__}: {exc}",
        )
    err = metrics.state_errors(res, ref, system.length_scale, system.omega, _moments(scene))
    failed = res.status in ("nan", "blowup", "solver_failed")
    errors = {"final": err.final, "linf": err.linf, "l2": err.l2, **metrics.qoi_errors(res, ref)}
    if failed:
        errors = {k: math.nan for k in errors}
    return Point(
        scene.name,
        integrator,
        setting,
        res.status,
        errors["final"],
        errors,
        res.invariant_drift,
        res.wall_s,
        res.n_force_evals,
        steps,
        rtol,
        res.status_detail,
    )


def work_precision(
    scene: Scene | str, cycles: float, ladder: Ladder, ref: Reference | None = None, progress=None
) -> SceneReport:
    """The whole sweep for one scene: reference, points, observed orders, cost-to-reach."""
    scene = _as_scene(scene)
    check_horizon(cycles, 1, len(scene.bodies))
    system = compile_scene(scene)
    ref = ref or reference(scene, cycles)
    points: list[Point] = []
    jobs = [(name, n, None) for name, ns in ladder.steps.items() for n in ns]
    jobs += [(name, None, r) for name, rs in ladder.rtols.items() for r in rs]
    for name, n, r in jobs:
        points.append(run_point(scene, system, ref.result, cycles, name, steps=n, rtol=r))
        if progress is not None:
            progress(points[-1])
    report = SceneReport(scene.name, cycles, ref, points)
    for name in ladder.steps:
        pts = [p for p in points if p.integrator == name]
        nominal = COMPOSITIONS[SPLITTINGS[name]][1]
        p_obs = metrics.observed_order([p.steps_per_period for p in pts], [p.error for p in pts])
        report.orders[name] = {
            "nominal": nominal,
            "observed": p_obs,
            "flag": bool(math.isfinite(p_obs) and abs(p_obs - nominal) > 0.3) or not math.isfinite(p_obs),
        }
    for name in {p.integrator for p in points}:
        pts = [p for p in points if p.integrator == name]
        report.cost[name] = {
            f"{t:g}": {
                "wall_s": metrics.cost_to_reach([(p.wall_s, p.error) for p in pts], t),
                "n_rhs": metrics.cost_to_reach([(float(p.n_rhs), p.error) for p in pts], t),
            }
            for t in TARGETS
        }
    return report


def speedup_at_equal_error(
    points: list[Point], fast: str = "splitting4", slow: str = "dop853", targets: tuple[float, ...] = TARGETS
) -> dict:
    """Wall-time ratio slow/fast at each target error both reach (Pareto interpolation).

    ``headline`` is the smallest ratio over the common targets (the conservative figure); if no
    listed target is common, the ratio at the smallest error the slow method reached.
    """
    pa = [(p.wall_s, p.error) for p in points if p.integrator == fast]
    pb = [(p.wall_s, p.error) for p in points if p.integrator == slow]
    ratios = {}
    for t in targets:
        a, b = metrics.cost_to_reach(pa, t), metrics.cost_to_reach(pb, t)
        if a and b:
            ratios[f"{t:g}"] = b / a
    if not ratios:
        front = metrics.pareto_front(pb)
        if front:
            t = front[-1][1]
            a = metrics.cost_to_reach(pa, t)
            if a:
                ratios[f"{t:.2g}"] = front[-1][0] / a
    return {"by_target": ratios, "headline": min(ratios.values()) if ratios else math.nan}


def require_target(report: SceneReport, target: float) -> dict:
    """Cheapest setting per integrator reaching ``target``; NumericsError if none does."""
    best = {}
    for name in {p.integrator for p in report.points}:
        ok = [p for p in report.points if p.integrator == name and np.isfinite(p.error) and p.error <= target]
        if ok:
            p = min(ok, key=lambda q: q.wall_s)
            best[name] = {"setting": p.setting, "error": p.error, "wall_s": p.wall_s}
    if not best:
        reached = min((p.error for p in report.points if np.isfinite(p.error)), default=math.nan)
        raise NumericsError(
            f"{report.scene}: no setting of the sweep reaches error {target:g} over {report.cycles:g} "
            f"cycles (best reached {reached:.2g}); refine the ladder (more steps per period, tighter "
            "rtol) or ask for a larger error"
        )
    return best
