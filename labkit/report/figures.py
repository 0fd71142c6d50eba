"""Figures for fits and reports (matplotlib's Agg canvas: no display, no global backend).

``fit_figure`` draws data (with error bars from the recorded spread when given) and the fitted
curve above, residuals below, axes labelled with quantity and unit; the paper's curve is drawn
dashed on top of the fit, so it stays visible where the two coincide. Speed sweeps are drawn
log-log like the paper's Fig. 5.25; spin-critical pairs like Fig. 6.18. Every figure is
written as PNG (150 dpi) and SVG beside it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib import rc_context
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter

from labkit.fit.overlay import Overlay
from labkit.fit.table_fit import FitReport
from labkit.report.labels import axis_label, residual_label

DPI = 150

LOG_LOG = {"power-law", "pfr-force", "mbs-distance"}
#: a log axis spanning less than this factor holds few ticks of mantissa 2, 3, 5 or 7: all are labelled
NARROW_LOG_SPAN = 2.0


def save(fig: Figure, path: str | Path, svg: bool = True, **kwargs) -> Path:
    """``path`` (PNG) and, with ``svg``, the same figure as SVG beside it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, **kwargs)
    if svg:
        with rc_context({"svg.fonttype": "none"}):   # text stays text: searchable, editable
            fig.savefig(path.with_suffix(".svg"), **kwargs)
    return path


def fit_figure(report: FitReport, path: str | Path, *, overlays: Sequence[Overlay] = (),
               title: str | None = None,
               errors: dict[str, tuple[np.ndarray | None, np.ndarray | None]] | None = None,
               svg: bool = False) -> Path:
    """Data + fitted curve (top) and residuals (bottom) for every series of ``report``.

    ``errors`` maps a series name to (x error, y error) arrays aligned with its points (one
    standard error or standard deviation, as recorded); None draws no bar. ``svg`` writes an
    SVG beside the PNG (the report does; ``labkit fit --plot`` writes only the file named)."""
    fig = Figure(figsize=(7.0, 6.5), dpi=DPI)
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(2, 1, height_ratios=[3, 1.3], hspace=0.08, left=0.14, right=0.97,
                          top=0.94, bottom=0.08)
    ax = fig.add_subplot(gs[0])
    axr = fig.add_subplot(gs[1], sharex=ax)
    colors = ["tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange", "tab:brown"]
    loglog = report.model in LOG_LOG
    for i, (name, res) in enumerate(report.series.items()):
        c = colors[i % len(colors)]
        label = "data" if name == "all" else f"series {name}"
        xerr, yerr = (errors or {}).get(name, (None, None))
        bars = xerr is not None or yerr is not None
        drawn = ax.errorbar(res.x, res.y, xerr=xerr, yerr=yerr, fmt="o", color=c, ms=5,
                            capsize=3 if bars else 0, elinewidth=1, zorder=3,
                            label=label + (" (bars: recorded spread)" if bars else ""))
        for axis_name, collection in zip(("x", "y"), _bar_collections(drawn, xerr, yerr), strict=True):
            if collection is not None:
                collection.set_gid(f"errorbar-{axis_name}-{name}")
        lo, hi = float(np.min(res.x)), float(np.max(res.x))
        grid = np.geomspace(lo, hi, 200) if loglog and lo > 0 else np.linspace(lo, hi, 200)
        ax.plot(grid, res.predict(grid), "-", color=c, lw=2.2, alpha=0.8, zorder=2,
                label=f"fit: {_param_text(res)}")
        r_err = residual_error(res, yerr)
        drawn_r = axr.errorbar(res.x, res.residuals, yerr=r_err, fmt="o", color=c, ms=4,
                               capsize=3 if r_err is not None else 0, elinewidth=1)
        if r_err is not None:   # the bars are the data's, in the residual's space (visible where the
            _bar_collections(drawn_r, None, r_err)[1].set_gid(f"errorbar-residual-{name}")  # data's hide)
    first = next(iter(report.series.values()))
    for ov in overlays:   # on top of the fit, dashed and dark: visible where they coincide
        if ov.fits(first.x_name, first.y_name):
            ax.plot(ov.x, ov.y, color="black", lw=1.3, dashes=(5, 3), zorder=4, label=ov.label)
    axr.axhline(0.0, color="0.5", lw=0.8)
    if loglog:
        ax.set_xscale("log")
        ax.set_yscale("log")
        for axis in (ax.xaxis, ax.yaxis, axr.xaxis):
            axis.set_major_formatter(FuncFormatter(_plain))
            axis.set_minor_formatter(FuncFormatter(_plain_minor))
        for axis, (low, high) in ((ax.yaxis, ax.get_ylim()), (axr.xaxis, ax.get_xlim())):
            if 0 < low and high < NARROW_LOG_SPAN * low:   # few of 2, 3, 5, 7 inside: label every tick
                axis.set_minor_formatter(FuncFormatter(_four_digits))
    ax.set_ylabel(axis_label(first.y_name))
    axr.set_xlabel(axis_label(first.x_name))
    axr.set_ylabel(f"residual in\n{residual_label(first.residual_space)}", fontsize=9)
    ax.tick_params(which="both", labelbottom=False)
    ax.grid(True, which="both", alpha=0.25)
    axr.grid(True, alpha=0.25)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(title or f"{report.model} fit", fontsize=11)
    return save(fig, path, svg=svg)  # fixed margins: "tight" would draw the figure twice


def residual_error(res, yerr) -> np.ndarray | None:
    """The data's y errors in the fit's residual space: as they are when the residuals are in y,
    relative (``yerr / y``) when they are in ``ln(y)``; None for another space or no errors."""
    if yerr is None:
        return None
    yerr = np.asarray(yerr, dtype=float)
    if res.residual_space == res.y_name:
        return yerr
    if res.residual_space == f"ln({res.y_name})":
        return yerr / np.abs(np.asarray(res.y, dtype=float))
    return None


def _bar_collections(drawn, xerr, yerr) -> tuple:
    """The x and y bar collections of an ``errorbar`` container (None where not drawn)."""
    bars = list(drawn.lines[2])
    x_bars = bars.pop(0) if xerr is not None and bars else None
    y_bars = bars.pop(0) if yerr is not None and bars else None
    return x_bars, y_bars


def _plain(v: float, _pos=None) -> str:
    return f"{v:g}"


def _four_digits(v: float, _pos=None) -> str:
    return f"{v:.4g}"


def _plain_minor(v: float, _pos=None) -> str:
    """Label minor log ticks with mantissa 2, 3, 5 or 7 only (readable, not crowded)."""
    if v <= 0:
        return ""
    mantissa = round(v / 10 ** math.floor(math.log10(v)), 6)
    return f"{v:g}" if mantissa in (2, 3, 5, 7) else ""


def _param_text(res) -> str:
    parts = []
    for k, p in res.params.items():
        if p.fixed:
            continue
        parts.append(f"{k} = {p.value:.4g} ± {p.stderr:.2g}")
    return ", ".join(parts)


def contact_sheet(frames: Sequence[np.ndarray], labels: Sequence[str], path: str | Path,
                  columns: int = 4) -> Path:
    """Frames (H x W x 3 BGR/RGB uint8 or H x W grey) in a grid with a label under each."""
    n = max(1, len(frames))
    rows = (n + columns - 1) // columns
    fig = Figure(figsize=(3.0 * columns, 2.6 * rows), dpi=100)
    FigureCanvasAgg(fig)
    for i, (frame, label) in enumerate(zip(frames, labels, strict=True)):
        ax = fig.add_subplot(rows, columns, i + 1)
        img = np.asarray(frame)
        if img.ndim == 3 and img.shape[2] == 3:
            img = img[:, :, ::-1]  # OpenCV BGR -> RGB
        ax.imshow(img, cmap="gray" if img.ndim == 2 else None)
        ax.set_title(label, fontsize=8)
        ax.axis("off")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    return path
