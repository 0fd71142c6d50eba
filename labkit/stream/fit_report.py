"""Rerun logging of fits (``labkit fit ... --rerun SPEC``): data and fitted curve over x.

Rerun's time-series view plots against a timeline, so the x column becomes an integer
sequence timeline named after it: ``x:<column>`` at 1-unit resolution when the data span at
least 100 units (RPM, rad/s), else the x values times a power of ten so that the span has at
least 100 ticks, named ``x:<column> (ticks of 1e-04)`` (e.g. ``distance_m``: 0.005-0.02 m
becomes ticks 50-200 of 1e-4 m; before, every x below 1 collapsed onto tick 0).
Entity paths, per series ``S``:

=========================  ================================================================
entity                      content
=========================  ================================================================
``/fit/S/data``            the measured y at each x (points)
``/fit/S/model``           the fitted curve sampled over the data range (line)
``/fit/S/residual``        data minus model at each x (points)
``/fit/S/summary``         text: parameters with standard errors and warnings
=========================  ================================================================
"""

from __future__ import annotations

from typing import Any

import numpy as np

from labkit.stream.core import RerunSpec, open_stream


def fit_blueprint(series: list[str], y_name: str = "y") -> Any:
    """Per series: data and fitted curve, residuals beneath (their own axis); then the
    parameters. Every x axis spans all the data."""
    import rerun.blueprint as rrb

    from labkit.stream.blueprints import whole_x_axis

    views: list[Any] = []
    for name in series:
        title = f"series {name}: {y_name}" if name != "all" else y_name
        views.append(rrb.TimeSeriesView(origin=f"/fit/{name}", name=f"{title}, data and fit",
                                        contents=["$origin/data", "$origin/model"], axis_x=whole_x_axis()))
        views.append(rrb.TimeSeriesView(origin=f"/fit/{name}", name=f"{title}, residual (data - fit)",
                                        contents=["$origin/residual"], axis_x=whole_x_axis()))
    shares = [3, 1] * len(series) + [1]
    return rrb.Blueprint(rrb.Vertical(*views, rrb.TextLogView(origin="/fit", name="parameters"),
                                      row_shares=shares), collapse_panels=True)


def x_timeline(x_name: str, x: np.ndarray) -> tuple[str, float]:
    """``(timeline name, factor)``: the ticks are ``round(x * factor)`` (see the module doc)."""
    base = f"x:{x_name}" if x_name else "x"
    finite = np.asarray(x, dtype=float)[np.isfinite(x)]
    span = float(np.ptp(finite)) if finite.size > 1 else 0.0
    if span <= 0 or span >= 100:
        return base, 1.0
    exponent = int(np.ceil(2.0 - np.log10(span)))
    return f"{base} (ticks of 1e{-exponent:+03d})", float(10.0**exponent)


def log_fit_report(rec: Any, report: Any, curve_samples: int = 200) -> None:
    """Log every series of a :class:`labkit.fit.table_fit.FitReport`."""
    import rerun as rr

    for name, fit in report.series.items():
        base = f"/fit/{name}"
        x = np.asarray(fit.x, dtype=float)
        y = np.asarray(fit.y, dtype=float)
        order = np.argsort(x)
        x, y = x[order], y[order]
        timeline, factor = x_timeline(fit.x_name, x)
        rec.log(f"{base}/data", rr.SeriesPoints(names=f"{fit.y_name} (data)", markers="circle",
                                                marker_sizes=4), static=True)
        rec.log(f"{base}/residual", rr.SeriesPoints(names="residual", markers="cross", marker_sizes=3),
                static=True)
        rec.log(f"{base}/model", rr.SeriesLines(names=f"{fit.model} fit", widths=2), static=True)
        ticks = np.round(x * factor).astype(np.int64)
        rec.send_columns(f"{base}/data", indexes=[rr.TimeColumn(timeline, sequence=ticks)],
                         columns=rr.Scalars.columns(scalars=y))
        rec.send_columns(f"{base}/residual", indexes=[rr.TimeColumn(timeline, sequence=ticks)],
                         columns=rr.Scalars.columns(scalars=y - np.asarray(fit.predict(x), dtype=float)))
        grid = np.unique(np.round(np.linspace(x.min(), x.max(), curve_samples) * factor).astype(np.int64))
        model = np.asarray(fit.predict(grid / factor), dtype=float)
        keep = np.isfinite(model)
        rec.send_columns(f"{base}/model", indexes=[rr.TimeColumn(timeline, sequence=grid[keep])],
                         columns=rr.Scalars.columns(scalars=model[keep]))
        text = ", ".join(f"{p} = {est.value:.5g} +/- {est.stderr:.2g}" for p, est in fit.params.items())
        warn = "; ".join(fit.warnings)
        rec.set_time(timeline, sequence=int(ticks[-1]))   # on the timeline: the text log lists it
        rec.log(f"{base}/summary", rr.TextLog(f"{name}: {text}" + (f" [warnings: {warn}]" if warn else ""),
                                             level="WARN" if warn else "INFO"))
        rec.disable_timeline(timeline)


def stream_fit_report(spec: RerunSpec | str, report: Any) -> None:
    first = next(iter(report.series.values()), None)
    y_name = first.y_name if first is not None else "y"
    rec = open_stream(spec, "labkit-fit", blueprint=fit_blueprint(list(report.series), y_name),
                      fallback_file="fit.rrd")
    try:
        log_fit_report(rec, report)
    finally:
        rec.flush()
        rec.disconnect()
