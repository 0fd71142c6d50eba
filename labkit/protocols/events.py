"""The run's event stream: typed documents (:mod:`labkit.documents`) handed to sinks.

Every document has ``t`` (clock seconds) and a ``type``; the table of types and fields is in
:mod:`labkit.documents`. A sink is anything with
``on_event(doc: RunDocument) -> None`` (the session writer, the progress bar, the rerun sink
of ``labkit.stream``). Sinks must not raise; :class:`EventBus` drops a sink that does and
reports it once on stderr so a broken viewer never stops a motor shutdown.

:class:`FlagTally` counts the flags device readings carried (``device_reset``,
``tare_lost``, ``overload``...): ``labkit run`` and ``labkit replay`` print it at the end.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import uuid
from collections.abc import Callable
from typing import Any, Protocol

from labkit.documents import (
    DOCUMENT_TYPES,
    ReadingEvent,
    RunDocument,
    RunStart,
    RunStop,
    Settled,
    StepStart,
    as_document,
    document_from_json,
)
from labkit.readings import READING_FLAGS


def new_run_id() -> str:
    """A fresh run id (a random uuid, as text)."""
    return str(uuid.uuid4())


class Sink(Protocol):
    def on_event(self, event: RunDocument) -> None: ...


class EventBus:
    """Fans each event out to the sinks; a failing sink is dropped, never fatal. Every document
    leaves it with the run's id, ``run_id`` (a new uuid unless given: a resumed run passes the
    id of the run it resumes)."""

    def __init__(self, sinks: list[Sink] | None = None, run_id: str | None = None) -> None:
        self.sinks: list[Sink] = list(sinks or [])
        self.run_id = run_id or new_run_id()

    def add(self, sink: Sink) -> None:
        self.sinks.append(sink)

    def emit(self, event: RunDocument | dict[str, Any]) -> None:
        """Hand ``event`` to every sink (a plain dict is first read as its document)."""
        event = as_document(event, 0.0)
        if event.run_id != self.run_id:
            event = dataclasses.replace(event, run_id=self.run_id)
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
        self.events: list[RunDocument] = []

    def on_event(self, event: RunDocument) -> None:
        self.events.append(event)

    def of_type(self, kind: str) -> list[RunDocument]:
        return [e for e in self.events if e.type == kind]


class FlagTally:
    """Counts the flags of the device readings of a run: ``{role: {flag: count}}``, with the
    clock time each flag was first seen."""

    def __init__(self) -> None:
        self.counts: dict[str, dict[str, int]] = {}
        self.first_t: dict[tuple[str, str], float] = {}

    def on_event(self, event: RunDocument) -> None:
        if isinstance(event, ReadingEvent):
            self.add(event.device, event.reading.flags, event.reading.t)

    def add(self, role: str, flags: Any, t: float) -> None:
        for flag in sorted(flags):
            per_role = self.counts.setdefault(role, {})
            per_role[flag] = per_role.get(flag, 0) + 1
            self.first_t.setdefault((role, flag), t)

    def summary(self, suspect_only: bool = False) -> str:
        """One line, e.g. ``balance: device_reset x1 (first at 7.20 s); balance: tare_lost x1 ...``;
        empty when no reading carried a flag. ``suspect_only``: only the flags that mean a value
        may be wrong (:data:`labkit.readings.READING_FLAGS`)."""
        parts = [f"{role}: {flag} x{n} (first at {self.first_t[(role, flag)]:.2f} s)"
                 for role, flags in sorted(self.counts.items()) for flag, n in sorted(flags.items())
                 if not suspect_only or READING_FLAGS.get(flag, (True, ""))[0]]
        return "; ".join(parts)


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

    def on_event(self, event: RunDocument) -> None:
        if isinstance(event, RunStart) and not event.dry_run:
            self.progress.start()
            self.task = self.progress.add_task("run", total=event.n_steps,
                                               protocol=event.protocol, state="starting")
        elif self.task is None:
            return
        elif isinstance(event, StepStart):
            self.progress.update(self.task, completed=event.index, state=f"step: {event.label}")
        elif isinstance(event, Settled):
            self.progress.update(self.task, state=f"settled in {event.settle_time_s:.1f} s, recording")
        elif event.type == "point":
            self.progress.update(self.task, completed=event["index"] + 1)
        elif event.type in ("interlock", "fault"):
            self.progress.update(self.task, state=f"[red]{event.type}: {event['reason']}")
        elif isinstance(event, RunStop):
            self.progress.update(self.task, state=event.status)
            self.progress.stop()
            return
        else:
            return
        self.progress.refresh()  # show each state change at once, not at the next auto-refresh


__all__ = ["DOCUMENT_TYPES", "EventBus", "FlagTally", "ListSink", "ProgressSink", "RunDocument", "Sink",
           "document_from_json"]


def not_logged(since: Callable[[float], list[Any]],
               mark: tuple[float, int]) -> tuple[list[Any], tuple[float, int]]:
    """The items ``since`` holds that were not logged yet, and the new mark. ``mark`` is (time of
    the last item logged, how many items of that time were): the lines of one read share its
    time, and a log may run while the reader is still adding them, so "after the last time" would
    lose the rest of them."""
    t_last, done = mark
    items = since(math.nextafter(t_last, -math.inf))
    new = items[done:]
    if not new:
        return [], mark
    t_new = new[-1].t
    return new, (t_new, sum(1 for item in items if item.t == t_new))
