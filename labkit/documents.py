"""The run's documents: one frozen dataclass per event type (bluesky's document model).

Every document has ``t`` (clock seconds), a class-level ``type`` (its name in
``events.jsonl``) and ``run_id``, the run's id (a uuid; the event bus stamps it, and a resumed
run carries the id of the run it resumes, so their documents join up).
:meth:`RunDocument.to_json` is the one place a document becomes JSON;
:func:`document_from_json` reads a line of ``events.jsonl`` (or a reading file) back.

=============  ================  ====================================================================
type           class             fields (SI values)
=============  ================  ====================================================================
start          RunStart          protocol, params, rig, n_steps, session (path or None),
                                 resumed_from, dry_run; what the protocol declares (ADR 0021):
                                 param_specs (unit, bounds), row (columns, units), hints
step           StepStart         index, n_steps, label, targets_rad_s {loop: rad/s}, eta_s
setpoint       Setpoint          loop, target_rad_s
settled        Settled           index, settle_time_s, speeds_rad_s {loop: rad/s}
control        ControlSnapshot   loops {name: {target_rad_s, setpoint_rad_s, measured_rad_s, duty,
                                 settled}}
descriptor     StreamDescriptor  device (the rig role), kind, driver, quantity, unit: a device's
                                 stream declared once, before its first reading (again if the
                                 device changes what it reports)
reading        ReadingEvent      device (the rig role), reading (the driver's
                                 :class:`~labkit.readings.Reading`, flags and raw bytes included;
                                 its JSON carries the values only: the descriptor has the units)
zero           Zeroed            device, value (balance reading at rest before zeroing), unit
point          PointDone         index, point (one result row, as written to results.json)
frames         FramesTaken       device, index, take, seqs, times, size, fmt, verdict, pattern,
                                 pattern_at_y (a camera burst a step analysed; the frames' bytes
                                 go to live sinks only, the frame cassette keeps them)
drop           Drop              index, trial, rotor_rad_s, spin_rad_s, cause
                                 ("balance"|"spin_loss"|"key"), hold_s
checkpoint     Checkpoint        index
stop_request   StopRequest       count (1: stop at next checkpoint; 2: safe state now)
interlock      Interlock         reason (every motor was commanded to zero), stop_failed
fault          Fault             reason (an exception ended the run; motors zeroed)
results        Results           results (the results.json object)
stop           RunStop           status ("completed"|"interrupted"|"failed"), reason, steps_done
=============  ================  ====================================================================

A reading is serialised by :class:`~labkit.readings.Reading` only: ``labkit probe`` prints
:meth:`~labkit.readings.Reading.as_json` (``t, quantity, value, unit, stable, overload, flags,
raw``); a run's reading files (``readings/ROLE.jsonl``) hold the stream's descriptor, then
:meth:`~labkit.readings.Reading.values_json` per reading (the same keys without quantity and unit).
Decision records: docs/decisions/0004-typed-run-documents.md,
docs/decisions/0033-one-reading-shape.md.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, ClassVar

from labkit.readings import Reading


@dataclass(frozen=True, kw_only=True)
class RunDocument:
    """Base of every run document: ``t`` is the clock time (s) of what it reports."""

    type: ClassVar[str] = ""
    t: float
    #: the run's id (a uuid, :class:`labkit.protocols.events.EventBus` stamps it; "" in
    #: sessions recorded before run ids)
    run_id: str = ""

    def to_json(self) -> dict[str, Any]:
        """The ``events.jsonl`` object: ``{"type": ..., "t": ..., <fields>}``."""
        out: dict[str, Any] = {"type": self.type, "t": self.t}
        for f in dataclasses.fields(self):
            if f.name != "t":
                out[f.name] = getattr(self, f.name)
        return out

    # Read-only mapping access by JSON key (``doc["reason"]``), for code that reads
    # events.jsonl and live documents alike.
    def __getitem__(self, key: str) -> Any:
        return self.to_json()[key]

    def get(self, key: str, default: Any = None) -> Any:
        return self.to_json().get(key, default)


@dataclass(frozen=True, kw_only=True)
class RunStart(RunDocument):
    """The run begins: what runs on which rig (``session`` is the directory, None without one)."""

    type: ClassVar[str] = "start"
    protocol: str
    params: dict[str, Any]
    rig: str
    n_steps: int
    session: str | None = None
    resumed_from: str | None = None
    dry_run: bool = False
    #: every parameter with its unit and bounds (:func:`labkit.protocols.declaration.param_specs`)
    param_specs: list[dict[str, Any]] | None = None
    #: the columns of a result row with their units (:class:`labkit.hints.Column`)
    row: list[dict[str, Any]] | None = None
    #: how the rows are drawn and fitted (:class:`labkit.hints.Hints` as JSON); None
    #: in sessions recorded before 0021: :mod:`labkit.protocols.legacy_hints` derives them
    hints: dict[str, Any] | None = None


@dataclass(frozen=True, kw_only=True)
class StepStart(RunDocument):
    """Step ``index`` of ``n_steps`` begins: its targets per speed loop and estimated duration."""

    type: ClassVar[str] = "step"
    index: int
    n_steps: int
    label: str
    targets_rad_s: dict[str, float]
    eta_s: float = 0.0


@dataclass(frozen=True, kw_only=True)
class Setpoint(RunDocument):
    """A speed loop got a new target."""

    type: ClassVar[str] = "setpoint"
    loop: str
    target_rad_s: float


@dataclass(frozen=True, kw_only=True)
class Settled(RunDocument):
    """Every loop held its target for the hold time; ``speeds_rad_s`` as measured then."""

    type: ClassVar[str] = "settled"
    index: int | None
    settle_time_s: float
    speeds_rad_s: dict[str, float | None] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class ControlSnapshot(RunDocument):
    """The speed loops' state (every 0.25 s): target, ramped setpoint, measured speed, duty."""

    type: ClassVar[str] = "control"
    loops: dict[str, dict[str, Any]]


@dataclass(frozen=True, kw_only=True)
class StreamDescriptor(RunDocument):
    """A device's stream of readings declared once, before its first reading (and again when
    the device changes what it reports, e.g. a balance switched from g to N): ``device`` the rig
    role, ``kind`` and ``driver`` as the rig file names them, and the ``quantity`` and SI
    ``unit`` of every following reading's ``value``."""

    type: ClassVar[str] = "descriptor"
    device: str
    kind: str = ""
    driver: str = ""
    quantity: str
    unit: str

    @classmethod
    def of(cls, device: str, reading: Reading, kind: str = "", driver: str = "",
           run_id: str = "") -> StreamDescriptor:
        """The descriptor of the stream ``reading`` begins (``t``: the reading's)."""
        return cls(t=reading.t, run_id=run_id, device=device, kind=kind, driver=driver,
                   quantity=reading.quantity, unit=reading.unit)

    def declares(self, reading: Reading) -> bool:
        """Whether ``reading`` has this stream's quantity and unit."""
        return reading.quantity == self.quantity and reading.unit == self.unit


@dataclass(frozen=True, kw_only=True)
class ReadingEvent(RunDocument):
    """One device reading; ``device`` is the rig role (the reading file's name). Its JSON
    carries the reading's values; quantity and unit are its stream's :class:`StreamDescriptor`'s."""

    type: ClassVar[str] = "reading"
    device: str
    reading: Reading

    @classmethod
    def of(cls, device: str, reading: Reading) -> ReadingEvent:
        return cls(t=reading.t, device=device, reading=reading)

    def to_json(self) -> dict[str, Any]:
        return {"type": self.type, "run_id": self.run_id, "device": self.device, **self.reading.values_json()}


@dataclass(frozen=True, kw_only=True)
class Zeroed(RunDocument):
    """A balance was zeroed; ``value`` is what it read at rest just before."""

    type: ClassVar[str] = "zero"
    device: str
    value: float
    unit: str


@dataclass(frozen=True, kw_only=True)
class PointDone(RunDocument):
    """Step ``index`` produced one result row (as written to results.json)."""

    type: ClassVar[str] = "point"
    index: int
    point: dict[str, Any]


@dataclass(frozen=True, kw_only=True)
class FramesTaken(RunDocument):
    """Step ``index`` analysed a burst of ``device`` (a camera role; ``take`` 1 for a retake):
    the frames' sequence numbers and times on the run's clock, their ``size`` [w, h], the
    analysis's ``verdict`` and ``pattern`` (the fitted trace in pixels, as ``labkit analyse``
    writes it) and ``pattern_at_y`` (``{"y": [...], "semi_axes_px": [[a, b], ...]}``: the
    pattern's semi-axes for values of the figure's y, so a sink can draw a fitted y on the frame
    without knowing the geometry). ``payloads``, the frames' bytes as stored, reach the live sinks
    only: events.jsonl keeps the rest, the frame cassette the bytes."""

    type: ClassVar[str] = "frames"
    device: str
    index: int
    take: int = 0
    seqs: list[int] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    size: list[int] = field(default_factory=list)
    fmt: str = "jpeg"
    verdict: str = ""
    pattern: dict[str, Any] | None = None
    pattern_at_y: dict[str, Any] | None = None
    payloads: tuple[bytes, ...] = field(default=(), repr=False)

    def to_json(self) -> dict[str, Any]:
        out = super().to_json()
        del out["payloads"]
        return out


@dataclass(frozen=True, kw_only=True)
class Drop(RunDocument):
    """spin-critical: the floator of trial ``trial`` dropped (``cause``: balance, spin_loss, key)."""

    type: ClassVar[str] = "drop"
    index: int
    trial: int
    rotor_rad_s: float
    spin_rad_s: float
    cause: str
    hold_s: float = float("nan")


@dataclass(frozen=True, kw_only=True)
class Checkpoint(RunDocument):
    """Step ``index`` is done and saved: a resumed run starts after it."""

    type: ClassVar[str] = "checkpoint"
    index: int


@dataclass(frozen=True, kw_only=True)
class StopRequest(RunDocument):
    """The operator or the system asked the run to stop (Ctrl-C, SIGTERM, SIGHUP, SIGQUIT)."""

    type: ClassVar[str] = "stop_request"
    #: how many times Ctrl-C was pressed: 1 stops at the next checkpoint, 2 zeroes every motor now
    count: int
    #: which signal asked ("SIGINT" for Ctrl-C, "SIGTERM", ...)
    signal: str = "SIGINT"


@dataclass(frozen=True, kw_only=True)
class Interlock(RunDocument):
    """An interlock tripped: every motor was commanded to zero (``stop_failed``: those that did
    not take the command)."""

    type: ClassVar[str] = "interlock"
    reason: str
    stop_failed: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"type": self.type, "t": self.t, "run_id": self.run_id, "reason": self.reason}
        if self.stop_failed:
            out["stop_failed"] = list(self.stop_failed)
        return out


@dataclass(frozen=True, kw_only=True)
class StopFailed(RunDocument):
    """A STOP could not be delivered to these motors (port gone, controller silent): the rotor
    may still turn, and the person at the rig must cut the motor's power (docs/explanation/safety.md)."""

    type: ClassVar[str] = "stop_failed"
    #: role -> why the STOP did not arrive ("port gone ...")
    devices: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class Fault(RunDocument):
    """An exception ended the run (``reason`` says which); every motor was commanded to zero."""

    type: ClassVar[str] = "fault"
    reason: str


@dataclass(frozen=True, kw_only=True)
class Results(RunDocument):
    type: ClassVar[str] = "results"
    #: the results.json object: protocol, points, fit
    results: dict[str, Any]


@dataclass(frozen=True, kw_only=True)
class RunStop(RunDocument):
    """The run ended: ``status`` completed, interrupted or failed, and why."""

    type: ClassVar[str] = "stop"
    status: str
    reason: str | None = None
    steps_done: int = 0


DOCUMENT_TYPES: dict[str, type[RunDocument]] = {
    cls.type: cls for cls in (RunStart, StepStart, Setpoint, Settled, ControlSnapshot, StreamDescriptor,
                              ReadingEvent, Zeroed, PointDone, FramesTaken, Drop, Checkpoint, StopRequest,
                              Interlock, StopFailed, Fault, Results, RunStop)
}


class UnknownDocument(ValueError):
    """A JSON object that is no run document (unknown ``type`` or a missing field)."""


def document_from_json(obj: dict[str, Any], stream: StreamDescriptor | None = None) -> RunDocument:
    """The document a line of ``events.jsonl`` was written from (inverse of ``to_json``); a
    reading's quantity and unit are its ``stream``'s (a reading written before descriptors
    carries its own).

    Raises :class:`UnknownDocument` naming the type and the missing field."""
    kind = obj.get("type")
    cls = DOCUMENT_TYPES.get(str(kind))
    if cls is None:
        known = ", ".join(sorted(DOCUMENT_TYPES))
        raise UnknownDocument(f"unknown run document type {kind!r}; known: {known}")
    if cls is ReadingEvent:
        # "device" of a reading document is the rig role; the driver's own name is not recorded
        reading = Reading.from_json({k: v for k, v in obj.items() if k != "device"},
                                    stream.quantity if stream else "", stream.unit if stream else "")
        return ReadingEvent(t=reading.t, run_id=str(obj.get("run_id", "")), device=str(obj.get("device", "")),
                            reading=reading)
    kwargs: dict[str, Any] = {"t": float(obj.get("t", 0.0))}
    for f in dataclasses.fields(cls):
        if f.name == "t":
            continue
        if f.name in obj:
            kwargs[f.name] = tuple(obj[f.name]) if f.name == "stop_failed" else obj[f.name]
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise UnknownDocument(f"{kind} document without {f.name!r}: {obj}")
    return cls(**kwargs)


def as_document(event: RunDocument | dict[str, Any], now: float) -> RunDocument:
    """``event`` itself, or the document a plain dict (``{"type": ..., ...}``) describes;
    a dict without ``t`` is stamped ``now``."""
    if isinstance(event, RunDocument):
        return event
    return document_from_json({"t": now, **event})
