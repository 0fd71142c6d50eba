"""Rerun sink of a protocol run (``labkit run`` / ``labkit demo`` / ``labkit replay``).

It is an event sink (:mod:`labkit.protocols.events`): it turns the run's typed documents
(:mod:`labkit.documents`) into rerun entities. Only entities the run has are logged (a rig
without a balance gets no force plot; a single loop gets no second speed plot). Each
quantity has one entity in one unit: speed in RPM (the rotor's tachometer is the loop's
measured speed, so it is not drawn twice), a balance as force in grams, a spin in rad/s.

Timelines: ``time`` (clock seconds since the start, a duration), ``step`` (protocol step) and
the figure's x timeline (:mod:`labkit.stream.blueprints`: ``rotor speed [RPM]`` for the
speed sweep, ``rotor speed [rad/s]`` for spin-critical), whose values are the x quantity.

The figure, its fit, its reference curve and its residuals are what the start document's
hints declare (:class:`labkit.hints.Hints`; the runner writes them, a replay re-runs the
protocol and so writes them too): this sink names no protocol (ADR 0021), and a run whose
protocol declares no hints gets the rig over time only.

=====================================  ======================================================
entity                                  content
=====================================  ======================================================
``/rig/<loop>/speed_rpm``              measured speed of each control loop (RPM)
``/rig/<loop>/setpoint_rpm``           ramped setpoint the loop is tracking (RPM)
``/rig/<loop>/target_rpm``             the step's target (RPM)
``/rig/<loop>/duty``                   commanded duty cycle (0..1, its own plot)
``/rig/<balance>/force_g``             balance readings as force in grams (mass kg x 1000,
                                       force N / g0 x 1000)
``/rig/<tach>/spin_rad_s``             a tachometer that is no loop's (the floator's spin)
``/rig/<device>/frame``                each reading's raw bytes (``raw``) and ``flags``
``<fig>/plot/data``                    one point per finished step on the x timeline (hints x, y)
``<fig>/plot/paper``                   the hints' reference curve (Fig. 5.25: y = 224e6 x^-1.9)
``<fig>/plot/fit/after_NN``            the fit after NN points with its 95 % band, logged at
                                       every point; earlier fits are cleared (static Clear)
``<fig>/residual/after_NN``            data minus fit of that fit, beneath the figure
``<fig>/also/<column>``                the hints' ``also`` columns against the same x, one panel each
``/events``                            text log: start, steps, settle, drops, interlocks, stop
``/camera/<device>/image``             a filmed burst's frames, the fitted trace and the trace
                                       at the live fit's y (:mod:`labkit.stream.frames`)
=====================================  ======================================================

``<fig>`` is the hints' root: ``/fig5_25`` (speed sweep) or ``/fig6_18`` (spin-critical). The
fits are :mod:`labkit.stream.livefit`'s for the hints' ``fit`` model, i.e. ``labkit fit``'s (ln F
for the power law, v for Eq. 6.37); residuals are ``ratio`` (%) or ``difference`` as hinted.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from labkit import documents as doc
from labkit.hints import Hints
from labkit.readings import READING_FLAGS
from labkit.stream.blueprints import FigureSpec, figure_of, run_blueprint
from labkit.stream.core import RerunSpec, open_stream
from labkit.stream.frames import CameraOverlays
from labkit.stream.livefit import LIVE_FITS, LiveFit, live_fit
from labkit.units import force_gf, rad_s_to_rpm

FIT_COLOURS = [[220, 40, 40], [240, 150, 150], [240, 150, 150]]
CURVE_SAMPLES = 120


#: longest wait for the viewer at the end of a run (s)
FLUSH_TIMEOUT_S = 5.0


class RerunRunSink:
    """Event sink streaming a run to rerun. ``close()`` flushes and writes the .rrd footer."""

    def __init__(self, rec: Any, loops: list[str] | None = None, devices: list[str] | None = None,
                 loop_tachs: set[str] | None = None) -> None:
        import rerun as rr

        self.rr = rr
        self.rec = rec
        self.loops = loops or ["rotor"]
        self.devices = list(devices or [])
        self.loop_tachs = loop_tachs if loop_tachs is not None else {f"{loop}_tach" for loop in self.loops}
        self.t0: float | None = None
        self.step: int = -1
        self.step_x: float | None = None
        self.protocol = ""
        self.hints: Hints | None = None   # the run's, None: no figure
        self.figure: FigureSpec | None = None
        self.points: list[tuple[float, float]] = []  # what the live fit uses
        self.fits: list[LiveFit] = []
        self.point_x: dict[int, float] = {}   # step -> the point's x (the camera overlays' fit)
        self.camera = CameraOverlays(rec, rr)
        self._styled: set[str] = set()
        #: device -> how its readings are drawn (from its stream's descriptor)
        self.series: dict[str, Series | None] = {}
        self.flush_error: str | None = None

    # ---- helpers ------------------------------------------------------------------------
    def _time(self, t: float) -> None:
        if self.t0 is None:
            self.t0 = t
        self.rec.set_time("time", duration=max(0.0, t - self.t0))
        if self.step >= 0:
            self.rec.set_time("step", sequence=self.step)

    def _style(self, path: str, style: Any) -> None:
        if path not in self._styled:
            self.rec.log(path, style, static=True)
            self._styled.add(path)

    def _scalar(self, path: str, value: float | None, name: str) -> None:
        if value is None or not np.isfinite(value):
            return
        self._style(path, self.rr.SeriesLines(names=name))
        self.rec.log(path, self.rr.Scalars(float(value)))

    def _text(self, text: str, level: str = "INFO") -> None:
        """An event on ``time`` and, once a step has a target, on the figure's x timeline too
        (the figure's tab opens on that timeline)."""
        if self.figure is not None and self.step_x is not None:
            self.rec.set_time(self.figure.timeline, sequence=int(round(self.step_x)))
        self.rec.log("/events", self.rr.TextLog(text, level=level))
        if self.figure is not None:
            self.rec.disable_timeline(self.figure.timeline)

    # ---- documents ----------------------------------------------------------------------
    def on_event(self, event: doc.RunDocument) -> None:
        if isinstance(event, doc.StepStart):
            self.step = event.index
        self._time(float(event.t))
        handler = getattr(self, f"_on_{event.type}", None)
        if handler is not None:
            handler(event)

    def _on_start(self, e: doc.RunStart) -> None:
        self.protocol = e.protocol
        self.hints = Hints.from_json(e.hints) if e.hints else None
        self.figure = figure_of(self.hints)
        if self.figure is not None:
            self.camera.timeline, self.camera.y_label = self.figure.timeline, self.figure.y_label
        self.rec.send_blueprint(run_blueprint(self.figure, self.loops, self.devices))
        self._text(f"start {self.protocol} on {e.rig} ({e.n_steps} steps)")
        if self.hints is not None and self.hints.fit and self.hints.fit not in LIVE_FITS:
            self._text(f"{self.protocol}: no live fit for model {self.hints.fit!r} (known: "
                       f"{', '.join(sorted(LIVE_FITS))}); points are drawn without a fit", "WARN")

    def _on_step(self, e: doc.StepStart) -> None:
        for loop, rad_s in e.targets_rad_s.items():
            self._scalar(f"/rig/{loop}/target_rpm", rad_s_to_rpm(rad_s), "target [RPM]")
        rotor = e.targets_rad_s.get(self.loops[0]) if self.loops else None
        if rotor is not None and self.hints is not None:
            self.step_x = self.hints.step_x(rotor)
        self._text(f"step {e.index}/{e.n_steps} {e.label}")

    def _on_control(self, e: doc.ControlSnapshot) -> None:
        for loop, snap in e.loops.items():
            for key, name in (("measured_rad_s", "speed_rpm"), ("setpoint_rad_s", "setpoint_rpm")):
                value = snap.get(key)
                self._scalar(f"/rig/{loop}/{name}", None if value is None else rad_s_to_rpm(value),
                             name.replace("_rpm", " [RPM]"))
            self._scalar(f"/rig/{loop}/duty", snap.get("duty"), "duty [0-1]")

    def _on_descriptor(self, e: doc.StreamDescriptor) -> None:
        """A device's stream: how its readings are drawn, decided once (:func:`reading_series`)."""
        self.series[e.device] = reading_series(e.device, e.quantity, e.unit, self.loop_tachs)

    def _on_reading(self, e: doc.ReadingEvent) -> None:
        """The value in the unit of its quantity (above, as its stream's descriptor declared);
        the frame's raw bytes and flags on ``/rig/<device>/frame``; a flagged reading also as a
        warning in ``/events``."""
        r = e.reading
        if e.device not in self.series:   # documents without a descriptor: the reading's own
            self.series[e.device] = reading_series(e.device, r.quantity, r.unit, self.loop_tachs)
        plotted = self.series[e.device]
        if plotted is not None:
            self._scalar(plotted.entity, plotted.value(r.value), plotted.legend)
            if e.device not in self.devices:   # a device the caller did not list (replay)
                self.devices.append(e.device)
                self.rec.send_blueprint(run_blueprint(self.figure, self.loops, self.devices))
        flags = ";".join(sorted(r.flags))
        self.rec.log(f"/rig/{e.device}/frame",
                     self.rr.AnyValues(raw=r.raw.decode("latin-1"), flags=flags))
        suspect = sorted(f for f in r.flags if READING_FLAGS.get(f, (True, ""))[0])
        if suspect:   # informational flags (zero_speed, stability_unknown) stay in the frame only
            self._text(f"{e.device}: {', '.join(suspect)} (raw {r.raw!r})", "WARN")

    def _on_frames(self, e: doc.FramesTaken) -> None:
        """A burst's frames with the fitted trace (a camera seen first gets its view)."""
        tick = int(round(self.step_x)) if self.step_x is not None and self.figure is not None else None
        if self.camera.frames(e, self.t0 or 0.0, tick):
            self.rec.send_blueprint(run_blueprint(self.figure, self.loops, self.devices, self.camera.devices))

    def _on_settled(self, e: doc.Settled) -> None:
        self._text(f"settled in {e.settle_time_s:.2f} s")

    def _on_drop(self, e: doc.Drop) -> None:
        self._text(f"drop ({e.cause}): rotor {e.rotor_rad_s:.0f} rad/s, spin {e.spin_rad_s:.0f} rad/s")

    def _on_interlock(self, e: doc.Interlock) -> None:
        self._text(f"interlock: {e.reason}; motors at zero", "ERROR")

    def _on_fault(self, e: doc.Fault) -> None:
        self._text(f"fault: {e.reason}; motors at zero", "ERROR")

    def _on_stop_request(self, e: doc.StopRequest) -> None:
        self._text(f"stop requested (Ctrl-C x{e.count})", "WARN")

    def _on_stop(self, e: doc.RunStop) -> None:
        level = "INFO" if e.status == "completed" else "WARN"
        self._text(f"stop: {e.status} after {e.steps_done} steps "
                   f"{'(' + str(e.reason) + ')' if e.reason else ''}", level)

    def _on_point(self, e: doc.PointDone) -> None:
        """The point on the figure, then the fit of every point so far with its band."""
        xy = self.hints.point_xy(e.point) if self.hints is not None else None
        if xy is None or self.figure is None:
            return
        verdict = e.point.get("verdict")
        if e.point.get("consistent") is False:  # its trials disagreed: drawn, not fitted (labkit fit too)
            self._text(f"point {xy[0]:.6g}, {xy[1]:.6g} left out of the live fit: its trials did not "
                       "agree (consistent: false)", "WARN")
        elif isinstance(verdict, str) and verdict != "ok":   # an analysis that doubts its own number
            why = "; ".join(map(str, e.point.get("reasons") or [])) or "no reason given"
            self._text(f"point {xy[0]:.6g}, {xy[1]:.6g} left out of the live fit: its analysis's verdict "
                       f"is {verdict} ({why})", "WARN")
        else:
            self.points.append(xy)
        fig = self.figure
        self._style(f"{fig.root}/plot/data", self.rr.SeriesPoints(
            names=fig.y_label, colors=[30, 110, 220], markers="circle", marker_sizes=5))
        self.rec.set_time(fig.timeline, sequence=int(round(xy[0])))
        self.rec.log(f"{fig.root}/plot/data", self.rr.Scalars(xy[1]))
        assert self.hints is not None
        for series, (path, _) in zip(self.hints.also, fig.also, strict=True):  # beside the figure
            more = self.hints.point_xy(e.point, series.y)
            if more is not None:
                self._style(path, self.rr.SeriesPoints(names=series.label, colors=[30, 110, 220],
                                                       markers="circle", marker_sizes=5))
                self.rec.log(path, self.rr.Scalars(more[1]))
        self.rec.disable_timeline(fig.timeline)
        self.point_x[e.index] = xy[0]
        fit = self._log_fit()
        self.camera.point(e.index, xy[1], verdict if isinstance(verdict, str) else "")
        if fit is not None:
            self.camera.refit(fit, self.point_x, float(e.t) - (self.t0 or 0.0))

    def _log_fit(self) -> LiveFit | None:
        """The live fit of the points so far, drawn with its band and residuals (None: none)."""
        fig, hints = self.figure, self.hints
        assert fig is not None and hints is not None
        xs, ys = [p[0] for p in self.points], [p[1] for p in self.points]
        fit = live_fit(hints.fit, xs, ys, hints.x_unit, hints.y_unit) if xs else None
        if fit is None:
            return None
        grid = np.unique(np.round(np.linspace(min(xs), max(xs), CURVE_SAMPLES)).astype(np.int64))
        if len(grid) < 2:
            return None
        if self.fits:   # only the newest fit is drawn: a static value shadows the temporal ones
            previous = f"after_{self.fits[-1].n:02d}"
            self.rec.log(f"{fig.root}/plot/fit/{previous}", self.rr.Scalars([np.nan] * 3), static=True)
            self.rec.log(f"{fig.root}/residual/{previous}", self.rr.Scalars([np.nan]), static=True)
        self.fits.append(fit)
        name = f"after_{fit.n:02d}"
        label = fit.label
        self.rec.log(f"{fig.root}/plot/fit/{name}", self.rr.SeriesLines(
            names=[label, "95 % band", "95 % band"], colors=FIT_COLOURS, widths=[2.5, 1, 1]), static=True)
        y, lo, hi = fit.curve(grid.astype(float))
        timeline = [self.rr.TimeColumn(fig.timeline, sequence=grid)]
        self.rec.send_columns(f"{fig.root}/plot/fit/{name}", indexes=timeline,
                              columns=self.rr.Scalars.columns(scalars=np.column_stack([y, lo, hi])))
        reference = hints.reference
        if reference is not None:
            self._style(f"{fig.root}/plot/paper", self.rr.SeriesLines(
                names=reference.live_label, colors=[120, 120, 120], widths=1.5))
            self.rec.send_columns(f"{fig.root}/plot/paper", indexes=timeline, columns=self.rr.Scalars.columns(
                scalars=reference.at(grid.astype(float))))
        x_pts = np.asarray(xs)
        fitted = fit.curve(x_pts)[0]
        residual = (100.0 * (np.asarray(ys) / fitted - 1.0) if hints.residual == "ratio"
                    else np.asarray(ys) - fitted)
        self.rec.log(f"{fig.root}/residual/{name}", self.rr.SeriesPoints(
            names="residual", colors=[30, 110, 220], markers="circle", marker_sizes=4), static=True)
        ticks = np.round(x_pts).astype(np.int64)
        self.rec.send_columns(f"{fig.root}/residual/{name}",
                              indexes=[self.rr.TimeColumn(fig.timeline, sequence=ticks)],
                              columns=self.rr.Scalars.columns(scalars=residual))
        return fit

    def close(self) -> None:
        """Flush (at most ``FLUSH_TIMEOUT_S``) and disconnect. A viewer that cannot be
        reached (``--rerun connect`` with none running) must not hang the end of a run whose
        session is already saved: the flush gives up and ``flush_error`` says why."""
        try:
            self.rec.flush(timeout_sec=FLUSH_TIMEOUT_S)
        except RuntimeError as exc:   # rerun: "gRPC has been unable to connect for ..."
            self.flush_error = str(exc)
        finally:
            self.rec.disconnect()


@dataclass(frozen=True)
class Series:
    """How a device stream is drawn (from its descriptor): the entity, its legend, and the
    unit its values are converted from (``grams``: a balance's force in grams-force, by
    :func:`labkit.units.force_gf`; else drawn as they come)."""

    entity: str
    legend: str
    unit: str = ""
    grams: bool = False

    def value(self, value: float) -> float:
        return force_gf(value, self.unit) if self.grams else value


def reading_series(device: str, quantity: str, unit: str, loop_tachs: set[str]) -> Series | None:
    """How a device's readings of ``quantity`` in ``unit`` are drawn, or None (the rotor's
    tachometer is the loop's measured speed, drawn once, in RPM)."""
    if (quantity, unit) in (("mass", "kg"), ("force", "N")):
        return Series(f"/rig/{device}/force_g", "force [g]", unit, grams=True)
    if quantity == "angular_speed":
        if device in loop_tachs:
            return None
        return Series(f"/rig/{device}/spin_rad_s", "spin [rad/s]")
    return Series(f"/rig/{device}/{quantity}", f"{quantity} [{unit}]")


def run_sink(spec: RerunSpec | str, session_path: str | Path | None,
             loops: list[str] | None = None, devices: list[str] | None = None,
             loop_tachs: set[str] | None = None) -> RerunRunSink:
    """Open a rerun stream for a run (``spawn`` without a display saves SESSION/run.rrd).
    The run's blueprint is sent when the run starts (its start document has the hints)."""
    fallback = Path(session_path or ".") / "run.rrd"
    loops, devices = loops or ["rotor"], devices or []
    rec = open_stream(spec, "labkit-run",
                      recording_id=Path(session_path).name if session_path else None,
                      blueprint=run_blueprint(None, loops, devices), fallback_file=fallback)
    return RerunRunSink(rec, loops, devices, loop_tachs)
