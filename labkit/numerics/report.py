"""Text tables, the JSON document and the plot of ``labkit bench sim`` (no physics here)."""

from __future__ import annotations

import math
import platform

from labkit.numerics.stress import Verdict
from labkit.numerics.workprecision import TARGETS, SceneReport


def fmt(x, spec: str = ".2e") -> str:
    if x is None:
        return "-"
    if isinstance(x, float) and not math.isfinite(x):
        return "nan"
    return format(x, spec)


def machine() -> dict:
    import os

    import numba
    import numpy
    import scipy

    return {
        "python": platform.python_version(),
        "cpu": platform.processor() or platform.machine(),
        "cores": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
    }


def scene_lines(rep: SceneReport) -> list[str]:
    lines = [f"scene {rep.scene}: {rep.cycles:g} cycles; reference: {rep.reference.description}"]
    head = (
        f"  {'integrator':<11} {'setting':<11} {'status':<8} {'err final':>9} {'err linf':>9} "
        f"{'cone err':>9} {'force err':>9} {'inv drift':>9} {'wall s':>9} {'n_rhs':>8}"
    )
    lines.append(head)
    for p in rep.points:
        e = p.errors
        lines.append(
            f"  {p.integrator:<11} {p.setting:<11} {('FAILED' if p.status == 'failed' else p.status):<8} "
            f"{fmt(p.error):>9} {fmt(e.get('linf')):>9} {fmt(e.get('cone_angle')):>9} "
            f"{fmt(e.get('mean_force')):>9} {fmt(p.invariant_drift):>9} {fmt(p.wall_s):>9} {p.n_rhs:>8}"
        )
        if p.status == "failed":
            lines.append(f"      -> {p.message}")
    for name, o in rep.orders.items():
        flag = "  <- differs from nominal by > 0.3" if o["flag"] else ""
        lines.append(f"  observed order {name}: {fmt(o['observed'], '.2f')} (nominal {o['nominal']}){flag}")
    lines.append("  cost to reach (wall s / force evaluations): " + "  ".join(f"{t:g}" for t in TARGETS))
    for name, cost in sorted(rep.cost.items()):
        cells = [f"{fmt(c['wall_s'], '.2g')}/{fmt(c['n_rhs'], '.2g')}" for c in cost.values()]
        lines.append(f"    {name:<11} " + "  ".join(f"{c:>13}" for c in cells))
    return lines


def verdict_lines(verdicts: list[Verdict]) -> list[str]:
    lines = ["stress cases (docs/reference/bench-sim.md#stress-cases):"]
    for v in verdicts:
        label = f"{v.name} ({v.id})" if v.name else v.id
        lines.append(f"  {label:<36} {'met    ' if v.met else 'NOT MET'}  {v.case}")
        lines.append(f"       criterion: {v.criterion}")
        nums = ", ".join(f"{k}={_short(x)}" for k, x in v.measured.items())
        lines.append(f"       measured ({v.cycles:g} cycles, {v.wall_s:.2g} s): {nums}")
        if v.detail:
            lines.append(f"       note: {v.detail}")
    met = sum(v.met for v in verdicts)
    lines.append(f"  {met}/{len(verdicts)} stress criteria met")
    return lines


def _short(x) -> str:
    if isinstance(x, bool) or x is None or isinstance(x, str | int):
        return str(x)
    return fmt(float(x), ".3g")


PLOT_METRICS = (
    ("final state error at t = kT (dimensionless)", lambda p: p.error),
    ("invariant drift (relative)", lambda p: p.invariant_drift),
    ("cone-angle error (rad)", lambda p: p.errors.get("cone_angle", math.nan)),
)


def plot(reports: list[SceneReport], path: str) -> None:
    """Wall time against each error metric (rows) for every scene (columns), one line per
    integrator; failed runs are drawn as red crosses at the right edge."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows, cols = len(PLOT_METRICS), len(reports)
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 3.8 * rows), squeeze=False)
    for c, rep in enumerate(reports):
        for r, (label, metric) in enumerate(PLOT_METRICS):
            ax = axes[r][c]
            for name in dict.fromkeys(p.integrator for p in rep.points):
                pts = [(metric(p), p.wall_s) for p in rep.points if p.integrator == name]
                ok = [(e, w) for e, w in pts if math.isfinite(e) and e > 0 and math.isfinite(w)]
                if ok:
                    ax.loglog(*zip(*ok, strict=True), "o-", label=name, markersize=4)
                failed = [p for p in rep.points if p.integrator == name and p.status == "failed"]
                if failed:
                    ax.plot([], [], "x", color="red", label=f"{name}: {len(failed)} failed")
            ax.set_xlabel(label)
            ax.set_ylabel("wall time (s), compile excluded")
            if r == 0:
                ax.set_title(f"{rep.scene} ({rep.cycles:g} cycles)")
            ax.grid(True, which="both", alpha=0.3)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
