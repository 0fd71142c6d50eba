"""Rerun sink of a protocol run (``labkit run`` / ``labkit demo`` / ``labkit replay``).

It is an event sink (:mod:`labkit.protocols.events`): it turns the run's typed documents
(:mod:`labkit.documents`) into rerun entities. Only entities the run has are logged (a rig
without a balance gets no force plot; a single loop gets no second speed plot).

Entity paths (timelines: ``time`` = clock seconds since start as a duration, ``step`` =
protocol step index):

=================================  ==========================================================
entity                              content
=================================  ==========================================================
``/rig/<loop>/speed_rpm``          measured speed of each control loop (Scalars)
``/rig/<loop>/setpoint_rpm``       ramped setpoint the loop is tracking
``/rig/<loop>/target_rpm``         the step's target
``/rig/<loop>/duty``               commanded duty cycle (0..1)
``/rig/<device>/<quantity>``       every device reading in SI (e.g. ``/rig/balance/force``, N)
``/rig/<device>/frame``            each reading's raw bytes (``raw``, latin-1 text) and flags
                                   (``flags``: e.g. ``device_reset;tare_lost``, empty if none)
``/results/points``                one point per finished step, x = speed (kRPM), y = force (g)
                                   for the sweep, x = rotor, y = spin (rad/s) for spin-critical
``/results/fit``                   the quick fit's curve over the points, updated each step
``/events``                        text log: start, steps, settle, drops, interlocks, stop
=================================  ==========================================================
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from labkit import documents as doc
from labkit.stream.core import RerunSpec, open_stream
from labkit.units import RAD_S_PER_RPM


def run_blueprint(loops: list[str], devices: list[str]) -> Any:
    """The views a user wants first: speeds, forces and the growing fit, then the log."""
    import rerun.blueprint as rrb

    series = [rrb.TimeSeriesView(origin=f"/rig/{loop}", name=f"{loop} speed (RPM)") for loop in loops]
    series += [rrb.TimeSeriesView(origin=f"/rig/{dev}", name=dev) for dev in devices]
    top = rrb.Horizontal(*series) if series else rrb.TextLogView(origin="/events", name="events")
    return rrb.Blueprint(
        rrb.Vertical(
            top,
            rrb.Horizontal(
                rrb.Spatial2DView(origin="/results", name="results and fit"),
                rrb.TextLogView(origin="/events", name="events"),
            ),
            row_shares=[3, 2],
        ),
        collapse_panels=True,
    )


#: longest wait for the viewer at the end of a run (s)
FLUSH_TIMEOUT_S = 5.0


class RerunRunSink:
    """Event sink streaming a run to rerun. ``close()`` flushes and writes the .rrd footer."""

    def __init__(self, rec: Any) -> None:
        import rerun as rr

        self.rr = rr
        self.rec = rec
        self.t0: float | None = None
        self.step: int = -1
        self.protocol = ""
        self.points: list[tuple[float, float]] = []
        self._styled: set[str] = set()
        self.flush_error: str | None = None

    # ---- helpers ------------------------------------------------------------------------
    def _time(self, t: float) -> None:
        if self.t0 is None:
            self.t0 = t
        self.rec.set_time("time", duration=max(0.0, t - self.t0))
        if self.step >= 0:
            self.rec.set_time("step", sequence=self.step)

    def _scalar(self, path: str, value: float | None, name: str) -> None:
        if value is None or not np.isfinite(value):
            return
        if path not in self._styled:
            self.rec.log(path, self.rr.SeriesLines(names=name), static=True)
            self._styled.add(path)
        self.rec.log(path, self.rr.Scalars(float(value)))

    def _text(self, text: str, level: str = "INFO") -> None:
        self.rec.log("/events", self.rr.TextLog(text, level=level))

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
        self._text(f"start {self.protocol} on {e.rig} ({e.n_steps} steps)")

    def _on_step(self, e: doc.StepStart) -> None:
        for loop, rad_s in e.targets_rad_s.items():
            self._scalar(f"/rig/{loop}/target_rpm", rad_s / RAD_S_PER_RPM, "target")
        self._text(f"step {e.index}/{e.n_steps} {e.label}")

    def _on_control(self, e: doc.ControlSnapshot) -> None:
        for loop, snap in e.loops.items():
            for key, name in (("measured_rad_s", "speed_rpm"), ("setpoint_rad_s", "setpoint_rpm")):
                value = snap.get(key)
                self._scalar(f"/rig/{loop}/{name}", None if value is None else value / RAD_S_PER_RPM,
                             name.replace("_rpm", ""))
            self._scalar(f"/rig/{loop}/duty", snap.get("duty"), "duty")

    def _on_reading(self, e: doc.ReadingEvent) -> None:
        """The value as a scalar; the frame's raw bytes and flags on ``/rig/<device>/frame``
        (``raw``, ``flags`` joined by ``;``); a flagged reading also as a warning in ``/events``."""
        r = e.reading
        self._scalar(f"/rig/{e.device}/{r.quantity}", r.value, f"{r.quantity} [{r.unit}]")
        flags = ";".join(sorted(r.flags))
        self.rec.log(f"/rig/{e.device}/frame",
                     self.rr.AnyValues(raw=r.raw.decode("latin-1"), flags=flags))
        if flags:
            self._text(f"{e.device}: {', '.join(sorted(r.flags))} (raw {r.raw!r})", "WARN")

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
        xy = point_xy(self.protocol, e.point)
        if xy is None:
            return
        self.points.append(xy)
        self.rec.log("/results/points", self.rr.Points2D(np.asarray(self.points), radii=0.15,
                                                         colors=[30, 110, 220]))

    def _on_results(self, e: doc.Results) -> None:
        fit = (e.results or {}).get("fit") or {}
        curve = fit_curve(self.protocol, fit, self.points)
        if curve is not None:
            self.rec.log("/results/fit", self.rr.LineStrips2D([curve], colors=[220, 60, 30]))

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


def point_xy(protocol: str, point: dict[str, Any]) -> tuple[float, float] | None:
    """The (x, y) a result row is drawn at in ``/results/points``."""
    if protocol == "speed-sweep" and point.get("force_g") is not None and point.get("speed_rpm"):
        return float(point["speed_rpm"]) / 1000.0, float(point["force_g"])
    if protocol == "spin-critical" and point.get("rotor_rad_s") is not None:
        return float(point["rotor_rad_s"]) / 100.0, float(point.get("spin_rad_s") or 0.0) / 100.0
    return None


def fit_curve(protocol: str, fit: dict[str, Any], points: list[tuple[float, float]]) -> np.ndarray | None:
    """The quick fit drawn over the points (power law y = a x^b, x in RPM, for the sweep)."""
    params = fit.get("params") or {}
    if protocol != "speed-sweep" or not points or "a" not in params or "b" not in params:
        return None
    a, b = params["a"]["value"], params["b"]["value"]
    xs = np.linspace(min(p[0] for p in points), max(p[0] for p in points), 64)
    return np.column_stack([xs, a * (xs * 1000.0) ** b])


def run_sink(spec: RerunSpec | str, session_path: str | Path | None,
             loops: list[str] | None = None, devices: list[str] | None = None) -> RerunRunSink:
    """Open a rerun stream for a run (``spawn`` without a display saves SESSION/run.rrd)."""
    fallback = Path(session_path or ".") / "run.rrd"
    rec = open_stream(spec, "labkit-run",
                      recording_id=Path(session_path).name if session_path else None,
                      blueprint=run_blueprint(loops or ["rotor"], devices or ["balance"]),
                      fallback_file=fallback)
    return RerunRunSink(rec)
