"""Rerun sink of a protocol run (``labkit run`` / ``labkit demo`` / ``labkit replay``).

It is an event sink (:mod:`labkit.protocols.events`): it turns the run's plain-dict events
into rerun entities. Only entities the run has are logged (a rig without a balance gets no
force plot; a single loop gets no second speed plot).

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
    def _time(self, event: dict[str, Any]) -> None:
        t = float(event.get("t", 0.0))
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

    # ---- events -------------------------------------------------------------------------
    def on_event(self, event: dict[str, Any]) -> None:
        kind = event.get("type")
        if kind == "step":
            self.step = int(event.get("index", self.step))
        self._time(event)
        handler = getattr(self, f"_on_{kind}", None)
        if handler is not None:
            handler(event)

    def _on_start(self, e: dict[str, Any]) -> None:
        self.protocol = str(e.get("protocol", ""))
        self._text(f"start {self.protocol} on {e.get('rig')} ({e.get('n_steps')} steps)")

    def _on_step(self, e: dict[str, Any]) -> None:
        targets = e.get("targets_rad_s") or {}
        for loop, rad_s in targets.items():
            self._scalar(f"/rig/{loop}/target_rpm", rad_s / RAD_S_PER_RPM, "target")
        label = e.get("label") or ""
        self._text(f"step {e.get('index')}/{e.get('n_steps')} {label}")

    def _on_control(self, e: dict[str, Any]) -> None:
        for loop, snap in (e.get("loops") or {}).items():
            for key, name in (("measured_rad_s", "speed_rpm"), ("setpoint_rad_s", "setpoint_rpm")):
                value = snap.get(key)
                self._scalar(f"/rig/{loop}/{name}", None if value is None else value / RAD_S_PER_RPM,
                             name.replace("_rpm", ""))
            self._scalar(f"/rig/{loop}/duty", snap.get("duty"), "duty")

    def _on_reading(self, e: dict[str, Any]) -> None:
        device, quantity = e.get("device", "device"), e.get("quantity", "value")
        self._scalar(f"/rig/{device}/{quantity}", e.get("value"), f"{quantity} [{e.get('unit', '')}]")

    def _on_settled(self, e: dict[str, Any]) -> None:
        self._text(f"settled in {e.get('settle_time_s', float('nan')):.2f} s")

    def _on_drop(self, e: dict[str, Any]) -> None:
        self._text(f"drop ({e.get('cause')}): rotor {e.get('rotor_rad_s', 0):.0f} rad/s, "
                   f"spin {e.get('spin_rad_s', 0):.0f} rad/s")

    def _on_interlock(self, e: dict[str, Any]) -> None:
        self._text(f"interlock: {e.get('reason')}; motors at zero", "ERROR")

    def _on_fault(self, e: dict[str, Any]) -> None:
        self._text(f"fault: {e.get('reason')}; motors at zero", "ERROR")

    def _on_stop_request(self, e: dict[str, Any]) -> None:
        self._text(f"stop requested (Ctrl-C x{e.get('count')})", "WARN")

    def _on_stop(self, e: dict[str, Any]) -> None:
        level = "INFO" if e.get("status") == "completed" else "WARN"
        self._text(f"stop: {e.get('status')} after {e.get('steps_done')} steps "
                   f"{'(' + str(e['reason']) + ')' if e.get('reason') else ''}", level)

    def _on_point(self, e: dict[str, Any]) -> None:
        point = e.get("point") or {}
        xy = point_xy(self.protocol, point)
        if xy is None:
            return
        self.points.append(xy)
        self.rec.log("/results/points", self.rr.Points2D(np.asarray(self.points), radii=0.15,
                                                         colors=[30, 110, 220]))

    def _on_results(self, e: dict[str, Any]) -> None:
        fit = (e.get("results") or {}).get("fit") or {}
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
