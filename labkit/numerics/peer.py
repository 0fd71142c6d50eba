"""labkit against the fair peer: a compiled DOP853 on the same equations, state and error metric.

The peer is CyRK's C++ DOP853 with a numba right-hand side (``cyrk-dop853``,
:mod:`labkit.sim.integrators.compiled_reference`); scipy's DOP853 runs the same compiled
right-hand side from Python. Both are measured in the same work-precision sweep as labkit's
splittings (same reference, same stroboscopic error, docs/explanation/numerics.md), and compared:

* **cost at equal error**: peer wall time / labkit wall time at every error target 1e-4 ... 1e-10
  that both reach (labkit: its cheapest splitting at that target; Pareto interpolation);
* **drift at equal cost**: labkit's default run over 1e4 cycles against the peer at the
  tolerance whose CPU cost matches it (from the sweep's power law, then one correction), run over
  the same 1e4 cycles; and labkit's ``kahanli8`` at no more force evaluations than its default.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from labkit.numerics import metrics
from labkit.numerics.workprecision import Ladder, SceneReport, work_precision
from labkit.sim import SimResult, compile_scene, load_scene, simulate
from labkit.sim.integrators import DEFAULT_INTEGRATOR, SPLITTINGS
from labkit.sim.integrators.splitting import COMPOSITIONS

PEER = "cyrk-dop853"
SCIPY = "dop853"
PEER_TARGETS = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
PEER_SCENES = ("conical_5_1", "mbs_fig6_1")  # one body; two bodies in a bound state
PEER_RTOLS = [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13]
LONG_CYCLES = 10_000


def peer_available() -> bool:
    """Whether CyRK (the ``bench`` extra) is installed."""
    from labkit.sim.integrators.compiled_reference import available

    return available()


def peer_ladder(quick: bool) -> Ladder:
    """The sweep for the comparison: labkit's splittings, the peer and scipy's DOP853."""
    steps = {"splitting4": [16, 32, 64, 128, 256, 512], "yoshida6": [8, 16, 32, 64, 128, 256],
             "kahanli8": [8, 12, 16, 24, 32, 48]}
    rtols = {PEER: list(PEER_RTOLS), SCIPY: [1e-6, 1e-9, 1e-12] if quick else list(PEER_RTOLS)}
    return Ladder(steps=steps, rtols=rtols)


@dataclass
class PeerComparison:
    """The comparison for one scene (rows of ``labkit bench sim``'s peer section)."""

    scene: str
    cycles: float
    by_target: dict = field(default_factory=dict)  # target -> {labkit, labkit_s, peer_s, scipy_s, ratio}
    min_ratio: float = math.nan
    drift: dict = field(default_factory=dict)
    report: SceneReport | None = field(default=None, repr=False)

    def to_json(self) -> dict:
        return {"scene": self.scene, "cycles": self.cycles, "by_target": self.by_target,
                "min_ratio_peer_over_labkit": self.min_ratio, "drift_1e4_cycles_at_equal_cost": self.drift}


def _cheapest_labkit(report: SceneReport, target: float) -> tuple[str | None, float | None]:
    best: tuple[str | None, float | None] = (None, None)
    for name in SPLITTINGS:
        pts = [(p.wall_s, p.error) for p in report.points if p.integrator == name]
        cost = metrics.cost_to_reach(pts, target) if pts else None
        if cost and (best[1] is None or cost < best[1]):
            best = (name, cost)
    return best


def _cost(report: SceneReport, integrator: str, target: float) -> float | None:
    pts = [(p.wall_s, p.error) for p in report.points if p.integrator == integrator]
    return metrics.cost_to_reach(pts, target) if pts else None


def ratios_at_targets(report: SceneReport, targets=PEER_TARGETS) -> tuple[dict, float]:
    """Peer / labkit (and scipy / labkit) wall-time ratio at each target both reach; the minimum."""
    rows = {}
    for t in targets:
        name, labkit_s = _cheapest_labkit(report, t)
        peer_s, scipy_s = _cost(report, PEER, t), _cost(report, SCIPY, t)
        rows[f"{t:g}"] = {
            "labkit": name,
            "labkit_s": labkit_s,
            "peer_s": peer_s,
            "scipy_s": scipy_s,
            "ratio": peer_s / labkit_s if peer_s and labkit_s else None,
            "scipy_ratio": scipy_s / labkit_s if scipy_s and labkit_s else None,
        }
    common = [r["ratio"] for r in rows.values() if r["ratio"] is not None]
    return rows, (min(common) if common else math.nan)


def _rtol_at_cost(report: SceneReport, wall_per_cycle: float) -> tuple[float, float]:
    """The peer's rtol whose cost per cycle matches ``wall_per_cycle``, and d log rtol / d log cost:
    a power law (log rtol linear in log cost) fitted to the sweep, so a cost outside the sweep is
    extrapolated, not clamped to its last rtol."""
    pts = [(p.wall_s / report.cycles, p.rtol) for p in report.points
           if p.integrator == PEER and p.rtol and math.isfinite(p.wall_s) and p.wall_s > 0]
    if len(pts) < 2:
        return (pts[0][1] if pts else math.nan), -8.0
    slope, intercept = np.polyfit(np.log([c for c, _ in pts]), np.log([r for _, r in pts]), 1)
    return float(np.clip(np.exp(intercept + slope * math.log(wall_per_cycle)), 1e-15, 1e-3)), float(slope)


def _cpu_run(scene, system, cycles: float, integrator: str, **kw) -> tuple[SimResult, float]:
    """One run and its CPU seconds (a shared machine's load disturbs CPU time far less than wall
    time, and the equal-cost tolerance depends on the cost to the eighth power)."""
    start = time.process_time()
    res = simulate(scene, cycles, integrator, system=system, samples_per_period=1, drift_threshold=math.inf,
                   rotation_threshold=math.inf, **kw)
    return res, time.process_time() - start


def drift_at_equal_cost(scene_name: str, report: SceneReport, cycles: float = LONG_CYCLES) -> dict:
    """labkit's default over ``cycles`` and the peer at the same CPU cost per cycle over the same
    cycles (the sweep's power law, then one correction along it); also labkit's 8th-order
    composition at no more force evaluations than the default."""
    scene = load_scene(scene_name)
    system = compile_scene(scene)
    _cpu_run(scene, system, 1, PEER, rtol=1e-6)  # load the compiled right-hand side
    ours, ours_cpu = _cpu_run(scene, system, cycles, DEFAULT_INTEGRATOR)
    scale = ours.wall_s / max(ours_cpu, 1e-9)  # the sweep's wall times, in this run's CPU terms
    rtol, slope = _rtol_at_cost(report, ours.wall_s / cycles)
    if not math.isfinite(rtol):
        return {}
    peer, peer_cpu = _cpu_run(scene, system, cycles, PEER, rtol=rtol)
    if not 0.8 < peer_cpu / ours_cpu < 1.25:  # one correction along the fitted power law
        rtol = float(np.clip(rtol * (ours_cpu / peer_cpu) ** slope, 1e-15, 1e-3))
        peer, peer_cpu = _cpu_run(scene, system, cycles, PEER, rtol=rtol)
    n8 = max(8, (ours.setting["stages"] * ours.setting["steps_per_period"])
             // len(COMPOSITIONS["kahanli8"][0]))
    if ours.integrator == "kahanli8" and ours.setting["steps_per_period"] == n8:
        high, high_cpu = ours, ours_cpu  # the default already is that run (auto, two free bodies)
    else:
        high, high_cpu = _cpu_run(scene, system, cycles, "kahanli8", steps_per_period=n8)
    return {
        "labkit": {"integrator": ours.integrator, "setting": ours.setting, "cpu_s": ours_cpu,
                   "wall_s": ours.wall_s, "invariant_drift": ours.invariant_drift},
        "labkit_order8": {"integrator": "kahanli8", "steps_per_period": n8, "cpu_s": high_cpu,
                          "wall_s": high.wall_s, "invariant_drift": high.invariant_drift},
        "peer": {"integrator": PEER, "rtol": rtol, "cpu_s": peer_cpu, "wall_s": peer.wall_s,
                 "invariant_drift": peer.invariant_drift, "status": peer.status},
        "cost_ratio_peer_over_labkit": peer_cpu / ours_cpu,
        "wall_over_cpu_labkit": scale,
    }


def compare(scene_name: str, cycles: float, quick: bool, long_cycles: float = LONG_CYCLES,
            progress=None) -> PeerComparison:
    """The whole comparison for one scene: sweep, ratios at targets, drift at equal cost."""
    report = work_precision(scene_name, cycles, peer_ladder(quick), progress=progress)
    rows, low = ratios_at_targets(report)
    drift = drift_at_equal_cost(scene_name, report, long_cycles)
    return PeerComparison(scene_name, cycles, rows, low, drift, report)


def peer_lines(comp: PeerComparison) -> list[str]:
    """The printed table of one comparison."""
    lines = [f"against a compiled DOP853 (CyRK C++ DOP853, numba RHS) on {comp.scene}, "
             f"{comp.cycles:g} cycles, same state and error metric:",
             "  target   labkit (cheapest)        labkit s   CyRK s     scipy s    CyRK/labkit  scipy/labkit"]

    def f(x, spec=".3g"):
        return "-" if x is None or not math.isfinite(x) else format(x, spec)

    for t, r in comp.by_target.items():
        lines.append(f"  {t:7s}  {str(r['labkit'] or '-'):22s}  {f(r['labkit_s'], '.2e'):9s}  "
                     f"{f(r['peer_s'], '.2e'):9s}  {f(r['scipy_s'], '.2e'):9s}  {f(r['ratio']):11s}  "
                     f"{f(r['scipy_ratio'])}")
    lines.append(f"  smallest CyRK/labkit ratio over the targets both reach: {f(comp.min_ratio)}"
                 + ("  (labkit slower where < 1)" if comp.min_ratio < 1 else ""))
    d = comp.drift
    if d:
        lines.append(
            f"  1e4 cycles at equal CPU cost: labkit's default ({d['labkit']['integrator']} "
            f"N={d['labkit']['setting']['steps_per_period']}) {d['labkit']['cpu_s']:.3g} s, drift "
            f"{f(d['labkit']['invariant_drift'], '.2e')}; CyRK rtol={d['peer']['rtol']:.2g} "
            f"{d['peer']['cpu_s']:.3g} s, drift {f(d['peer']['invariant_drift'], '.2e')} "
            f"(cost ratio {d['cost_ratio_peer_over_labkit']:.2f})"
        )
        o8 = d["labkit_order8"]
        lines.append(f"  labkit kahanli8 N={o8['steps_per_period']} (<= the default's force evaluations): "
                     f"{o8['cpu_s']:.3g} s, drift {f(o8['invariant_drift'], '.2e')}")
    return lines
