"""Rerun blueprints of a protocol run: the paper's figure as an x-y plot, the rig over time.

Rerun's time-series view plots scalars against the timeline selected in the time panel, and
that choice is global (one timeline for every view: rerun issues #6828, #8050). An x-y plot
is therefore a time-series view on a timeline whose values are the x quantity, named by the
protocol's hints (``rotor speed [RPM]`` for Fig. 5.25, ``rotor speed [rad/s]`` for Fig. 6.18,
integer sequences at 1 RPM or 1 rad/s resolution). Everything about the figure comes from the
run's hints (:class:`labkit.hints.Hints`, ADR 0021); no protocol is named here.
The blueprint opens on that timeline, in a tab with the figure, its residuals and the events;
the rig's speed, duty and readings over the ``time`` timeline are a second tab (select the
``time`` timeline to see them). No spatial view draws results (a 2-D spatial view has image
coordinates, y down, and no axes); a run that films gets one beside the figure per camera,
with the frames and the traces drawn on them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class FigureSpec:
    """What a protocol's x-y figure plots: timeline (x), entity root, titles, units."""

    title: str
    timeline: str
    root: str
    y_label: str
    residual_label: str
    legend_corner: str = "RightTop"
    tab: str = ""
    #: more quantities against the same x: (entity, panel title) each (the hints' ``also``)
    also: tuple[tuple[str, str], ...] = ()


def figure_of(hints: Any) -> FigureSpec | None:
    """The figure a run's hints (:class:`labkit.hints.Hints`) describe; None without."""
    if hints is None:
        return None
    also = tuple((f"{hints.entity_root}/also/{s.y}", f"{s.label} against {hints.x_label}")
                 for s in getattr(hints, "also", ()))
    return FigureSpec(hints.figure_title, hints.x_label, hints.entity_root, hints.y_label,
                      hints.residual_label, hints.legend_corner, hints.figure or hints.figure_title, also)


def whole_x_axis() -> Any:
    """A time axis showing the whole run (every blueprint view of a run uses it)."""
    import rerun.blueprint as rrb

    everything = rrb.components.TimeRange(start=rrb.TimeRangeBoundary.infinite(),
                                          end=rrb.TimeRangeBoundary.infinite())
    return rrb.TimeAxis(link="Independent", view_range=everything)


def figure_views(figure: FigureSpec) -> list[Any]:
    """The figure (data, paper curve, fit and band) and its residuals beneath."""
    import rerun.blueprint as rrb

    return [
        rrb.TimeSeriesView(origin=f"{figure.root}/plot", name=figure.title, axis_x=whole_x_axis(),
                           plot_legend=rrb.PlotLegend(corner=figure.legend_corner)),
        rrb.TimeSeriesView(origin=f"{figure.root}/residual", name=figure.residual_label,
                           axis_x=whole_x_axis(), plot_legend=rrb.PlotLegend(visible=False)),
    ]


def rig_views(loops: list[str], devices: list[str]) -> list[Any]:
    """Speed (RPM, with setpoint and target), duty (0-1, its own axis), and each device's
    readings in their own unit, over the ``time`` timeline."""
    import rerun.blueprint as rrb

    views = []
    for loop in loops:
        views.append(rrb.TimeSeriesView(
            origin=f"/rig/{loop}", name=f"{loop} speed [RPM]", axis_x=whole_x_axis(),
            contents=["$origin/speed_rpm", "$origin/setpoint_rpm", "$origin/target_rpm"]))
        views.append(rrb.TimeSeriesView(origin=f"/rig/{loop}", name=f"{loop} duty [0-1]",
                                        axis_x=whole_x_axis(), contents=["$origin/duty"]))
    for dev in devices:
        views.append(rrb.TimeSeriesView(origin=f"/rig/{dev}", name=f"{dev} readings", axis_x=whole_x_axis(),
                                        contents=["$origin/**", "- $origin/frame"]))
    return views


def camera_views(cameras: list[str]) -> list[Any]:
    """One 2-D view per camera: its frames, the trace the analysis fitted (green) and the trace
    at the live fit's y (red) (:mod:`labkit.stream.frames`)."""
    import rerun.blueprint as rrb

    return [rrb.Spatial2DView(origin=f"/camera/{cam}", name=f"{cam}: fitted trace (green), live fit (red)")
            for cam in cameras]


def run_blueprint(figure: FigureSpec | None, loops: list[str], devices: list[str],
                  cameras: list[str] | None = None) -> Any:
    """The blueprint of a run: its figure's tab first (when the run has a figure; the cameras'
    frames beside it), the rig over time next."""
    import rerun.blueprint as rrb

    events = rrb.TextLogView(origin="/events", name="events")
    rig = rrb.Vertical(*rig_views(loops, devices), name="rig over time (timeline: time)")
    films = camera_views(list(cameras or []))
    if figure is None:
        body = rrb.Horizontal(rig, *films, column_shares=[3] + [2] * len(films)) if films else rig
        return rrb.Blueprint(rrb.Vertical(body, events, row_shares=[3, 1]), rrb.TimePanel(timeline="time"),
                             collapse_panels=True)
    plot, residual = figure_views(figure)
    more = [rrb.TimeSeriesView(origin=origin, name=title, axis_x=whole_x_axis(),
                               plot_legend=rrb.PlotLegend(visible=False)) for origin, title in figure.also]
    if films:
        charts = rrb.Vertical(plot, residual, *more, row_shares=[5, 2, *([3] * len(more))])
        top = rrb.Horizontal(charts, rrb.Vertical(*films), column_shares=[3, 2])
        tab = rrb.Vertical(top, events, row_shares=[7, 2], name=figure.tab or figure.title)
    else:
        tab = rrb.Vertical(plot, residual, *more, events, row_shares=[5, 2, *([3] * len(more)), 2],
                           name=figure.tab or figure.title)
    return rrb.Blueprint(rrb.Tabs(tab, rig, active_tab=0),
                         rrb.TimePanel(timeline=figure.timeline, play_state="paused"),
                         collapse_panels=True)


def view_kinds(blueprint: Any) -> list[tuple[str, str]]:
    """``(view class, origin)`` of every view in a blueprint (walks its containers)."""
    out: list[tuple[str, str]] = []

    def walk(node: Any) -> None:
        if hasattr(node, "class_identifier"):   # a view
            out.append((str(node.class_identifier), str(node.origin)))
            return
        for child in getattr(node, "contents", None) or ():
            walk(child)

    walk(blueprint.root_container)
    return out
