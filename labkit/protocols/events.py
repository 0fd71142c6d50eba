"""The run's event stream: plain dicts handed to pluggable sinks.

Every event has ``type`` and ``t`` (clock seconds). Types and their keys (SI values):

=============  ==================================================================================
type           keys
=============  ==================================================================================
start          protocol, params, rig, n_steps, session (path or None), resumed_from, dry_run
step           index, n_steps, label, targets_rad_s {loop: rad/s}, eta_s
setpoint       loop, target_rad_s
settled        index, settle_time_s, speeds_rad_s {loop: rad/s}
control        loops {name: {target_rad_s, setpoint_rad_s, measured_rad_s, duty, settled}}
reading        device, quantity, value, unit, stable, overload
zero           device, value (balance reading at rest before zeroing, in its unit), unit
point          index, point (one result row, as written to results.json)
drop           index, trial, rotor_rad_s, spin_rad_s, cause ("balance"|"spin_loss"|"key")
checkpoint     index
stop_request   count (1: stop at next checkpoint; 2: safe state now), signal ("SIGINT", "SIGTERM"...)
interlock      reason (every motor was commanded to zero), stop_failed (those not delivered)
stop_failed    devices {role: why}: a STOP could not be delivered (docs/safety.md)
fault          reason (an exception ended the run; motors zeroed)
results        results (the results.json object)
stop           status ("completed"|"interrupted"|"failed"), reason, steps_done
=============  ==================================================================================

A sink is anything with ``on_event(event: dict) -> None`` (the session writer, the progress
bar, the rerun sink of ``labkit.stream``). Sinks must not raise; :class:`EventBus` drops a
sink that does and reports it once on stderr so a broken viewer never stops a motor
shutdown.
"""

from __future__ import annotations

import sys
from typing import Any, Protocol


class Sink(Protocol):
    def on_event(self, event: dict[str, Any]) -> None: ...


class EventBus:
    """Fans each event out to the sinks; a failing sink is dropped, never fatal."""

    def __init__(self, sinks: list[Sink] | None = None) -> None:
        self.sinks: list[Sink] = list(sinks or [])

    def add(self, sink: Sink) -> None:
        self.sinks.append(sink)

    def emit(self, event: dict[str, Any]) -> None:
        for sink in list(self.sinks):
            try:
                sink.on_event(event)
            except Exception as exc:  # noqa: BLE001 - a sink must never break the run
                self.sinks.remove(sink)
                print(f"labkit: event sink {type(sink).__name__} failed and was dropped: {exc}",
                      file=sys.stderr)


class ListSink:
    """Keeps every event in memory (tests, replay comparison)."""

    def __init__(self) -> None:
        self.events: list[dict[str, Any]] = []

    def on_event(self, event: dict[str, Any]) -> None:
        self.events.append(event)

    def of_type(self, kind: str) -> list[dict[str, Any]]:
        return [e for e in self.events if e.get("type") == kind]


class ProgressSink:
    """A rich progress bar: step k/N, ETA, current settle state. Quiet when not a terminal."""

    def __init__(self, console: Any = None) -> None:
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

        self.console = console or Console(stderr=True)
        self.progress = Progress(
            TextColumn("[bold]{task.fields[protocol]}"), BarColumn(), MofNCompleteColumn(),
            TimeRemainingColumn(), TextColumn("{task.fields[state]}"),
            console=self.console, transient=False, disable=not self.console.is_terminal,
        )
        self.task: Any = None

    def on_event(self, event: dict[str, Any]) -> None:
        kind = event.get("type")
        if kind == "start" and not event.get("dry_run"):
            self.progress.start()
            self.task = self.progress.add_task("run", total=event["n_steps"],
                                               protocol=event["protocol"], state="starting")
        elif self.task is None:
            return
        elif kind == "step":
            self.progress.update(self.task, completed=event["index"], state=f"step: {event['label']}")
        elif kind == "settled":
            self.progress.update(self.task, state=f"settled in {event['settle_time_s']:.1f} s, recording")
        elif kind == "point":
            self.progress.update(self.task, completed=event["index"] + 1)
        elif kind in ("interlock", "fault"):
            self.progress.update(self.task, state=f"[red]{kind}: {event['reason']}")
        elif kind == "stop":
            self.progress.update(self.task, state=event["status"])
            self.progress.stop()
            return
        else:
            return
        self.progress.refresh()  # show each state change at once, not at the next auto-refresh
