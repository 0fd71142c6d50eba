"""Plain-text table of a fit report (what ``labkit fit`` prints)."""

from __future__ import annotations

from labkit.fit.models import MODELS
from labkit.fit.table_fit import FitReport


def _g(v: float) -> str:
    return f"{v:.5g}"


def format_report(report: FitReport) -> str:
    spec = MODELS[report.model]
    cols = ", ".join(f"{k}={v}" for k, v in report.columns.items())
    lines = [f"{report.model}: {spec.equation}", f"source: {report.source}  ({cols})"]
    for name, res in report.series.items():
        lines.append("")
        lines.append(f"series {name}: n = {res.n}, dof = {res.dof}, rms residual = {res.rms_residual:.4g} "
                     f"[{res.residual_space}], R^2 = {res.r_squared:.5f}")
        lines.append(f"  {'param':<12}{'value':>14}{'stderr':>12}   {'95 % interval':<28}unit")
        for k, p in res.params.items():
            if p.fixed:
                lines.append(f"  {k:<12}{_g(p.value):>14}{'(fixed)':>12}   {'':<28}{p.unit}")
                continue
            ci = f"[{_g(p.ci95[0])}, {_g(p.ci95[1])}]"
            tag = " (derived)" if p.derived else ""
            lines.append(f"  {k:<12}{_g(p.value):>14}{p.stderr:>12.3g}   {ci:<28}{p.unit}{tag}")
            if p.bootstrap_ci95 is not None:
                bci = f"[{_g(p.bootstrap_ci95[0])}, {_g(p.bootstrap_ci95[1])}]"
                lines.append(f"  {'':<12}{'':>14}{'bootstrap':>12}   {bci:<28}")
        for w in res.warnings:
            lines.append(f"  WARNING: {w}")
    return "\n".join(lines)
