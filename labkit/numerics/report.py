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
    lines = ["stress cases (NUMERICS.md 5.4):"]
    for v in verdicts:
        lines.append(f"  {v.id:<4} {'met    ' if v.met else 'NOT MET'}  {v.case}")
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


def plot(reports: list[SceneReport], path: str) -> None:
    """Wall time against final state error, one panel per scene, one line per integrator."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(reports), figsize=(5.5 * len(reports), 4.5), squeeze=False)
    for ax, rep in zip(axes[0], reports, strict=True):
        for name in dict.fromkeys(p.integrator for p in rep.points):
            pts = [(p.error, p.wall_s) for p in rep.points if p.integrator == name]
            ok = [(e, w) for e, w in pts if math.isfinite(e) and e > 0 and math.isfinite(w)]
            if ok:
                ax.loglog(*zip(*ok, strict=True), "o-", label=name)
            bad = [w for e, w in pts if not (math.isfinite(e) and e > 0) and math.isfinite(w)]
            if bad:
                ax.loglog([1.0] * len(bad), bad, "x", color="red", label=f"{name} failed")
        ax.set_xlabel("final state error at t = kT (dimensionless)")
        ax.set_ylabel("wall time (s), compile excluded")
        ax.set_title(f"{rep.scene} ({rep.cycles:g} cycles)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
