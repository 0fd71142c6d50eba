"""``labkit replay``: a session's serial traffic through the same protocol code, at three levels
(docs/explanation/replay.md, docs/decisions/0019-faithful-replay.md).

* **exact** (sessions recorded on the virtual clock): every port is ``replay://...?mode=timed``,
  what the drivers send must match the recording byte for byte, and the results must equal
  ``results.json`` (fits within :data:`~labkit.protocols.replay_compare.REPLAY_FIT_RTOL`).
* **faithful** (sessions recorded on the real clock): every port is
  ``replay://...?mode=faithful`` on a virtual clock started at the recording's clock reading;
  device bytes arrive at their recorded times, writes are matched by content within a
  window, and the run must take the same decisions (:func:`~labkit.protocols.replay_compare.decisions`)
  with its points within :data:`~labkit.protocols.replay_compare.POINT_TOLERANCES`, and the
  recorded fit must be the fit of the recorded points (:func:`recorded_fit_diffs`). A camera's
  frame cassette is served at its recorded times (:mod:`labkit.devices.camera.faithful`;
  docs/decisions/0036-camera-frames-in-a-faithful-replay.md).
* **analysis** (any session, also from an older labkit): no protocol run; the recorded
  bytes re-parsed by today's drivers (:mod:`labkit.protocols.reanalyse`).

``level="auto"`` picks exact or faithful from the clock ``run.json`` names.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from labkit.errors import CassetteError, LabkitError
from labkit.hints import analysis_keys
from labkit.io.clock import VirtualClock, recorded_runs, recorded_ticks, use_clock
from labkit.io.replay_clock import ReplayClock
from labkit.protocols.analysis_versions import CrossVersion, cross_version, diff_points_then_fit
from labkit.protocols.events import Sink
from labkit.protocols.params import resolve_params
from labkit.protocols.reading_evidence import faithful_reading_diffs
from labkit.protocols.recorded import recorded_points, replay_url
from labkit.protocols.registry import get_protocol
from labkit.protocols.replay_compare import (
    DERIVED_KEYS,
    ReplayOutcome,
    decisions,
    diff_decisions,
    diff_results,
    diff_within,
    offline_wording,
)
from labkit.protocols.replay_evidence import Evidence, diff_points
from labkit.protocols.resume import check_carried_points
from labkit.protocols.runner import Runner, normalise
from labkit.rig import load_rig
from labkit.session import SessionRecord, load_session_record
from labkit.session.integrity import integrity_problems
from labkit.session.paths import session_file

LEVELS = ("auto", "exact", "faithful", "analysis")
#: the frame of a clock read's site where the run begins (labkit.io.clock.read_site): a stand-still
#: in the runner itself (a burst's analysis after a camera's last step) matches whoever called it
RUN_SITE = f"{Runner.__module__.rsplit('.', 1)[-1]}.py:{Runner.run.__qualname__}+"
#: events a replay does not read (the control loop's ticks: most of a long session's events.jsonl)
REPLAY_SKIPS = frozenset({"control"})
LEVEL_WORDS = {
    "exact": "exact (virtual-clock session: every byte as recorded, results identical)",
    "faithful": "faithful (real-clock session: device bytes at their recorded times, writes matched "
                "by content; same decisions, points within tolerance)",
    "analysis": "analysis only (recorded bytes re-parsed by today's drivers; no protocol run)",
}


class _Collect:
    """Sink keeping the replay's step, settle, drop, interlock, fault and stop documents."""

    KEEP = frozenset({"step", "settled", "drop", "interlock", "fault", "stop"})

    def __init__(self) -> None:
        self.events: list[Any] = []

    def on_event(self, event: Any) -> None:
        if event.get("type") in self.KEEP:
            self.events.append(event)


class _StepPacer:
    """Sink holding a faithful replay's protocol at each step's start until the recording's
    step began, and at each step's point until the recording's point was made: between steps
    the recorded program may have stood still (writing its files on a loaded PC) in code that
    records nothing, and a step begun early settles early; an analysis at the step's end
    (a strobe clip's, seconds of CPU on a loaded PC) takes no time in the replay, whose run would
    otherwise end, and stop its motor, before the recording's did."""

    PACED = ("step", "point")

    def __init__(self, clock: ReplayClock, record: SessionRecord) -> None:
        self.clock = clock
        self.times = {(e.get("type"), e.get("index")): float(e["t"]) for e in record.events
                      if e.get("type") in self.PACED and isinstance(e.get("t"), int | float)}

    def on_event(self, event: Any) -> None:
        if event.get("type") in self.PACED:
            recorded = self.times.get((event.get("type"), event.get("index")))
            if recorded is not None and recorded > self.clock.now():
                self.clock.sleep_until(recorded)


def recorded_clock(record: SessionRecord) -> str:
    """``virtual`` or ``real``: the clock a session ran on (sessions without the key: virtual,
    the only kind an older labkit replayed)."""
    return "real" if record.meta.get("clock") == "real" else "virtual"


def choose_level(record: SessionRecord, level: str = "auto") -> str:
    """``level``, or for ``auto``: exact for a virtual-clock session, faithful for a real-clock
    one whose cassettes carry their clock origin (labkit since 2026-11-27), else analysis."""
    if level not in LEVELS:
        raise LabkitError(f"replay level {level!r}: choose one of {', '.join(LEVELS)}")
    if level != "auto":
        return level
    if recorded_clock(record) == "virtual":
        return "exact"
    return "faithful" if faithful_gap(record) is None else "analysis"


def faithful_gap(record: SessionRecord) -> str | None:
    """None when a real-clock session can be replayed faithfully: it kept its speed loop's ticks
    (``clock.jsonl``) and every serial cassette names its clock origin (a frame cassette's
    frames carry their clock readings); else what it lacks (older real-clock sessions cannot be
    put on one time line: they are re-analysed instead)."""
    import json

    from labkit.io.clock import TICKS_FILE

    if not (record.path / TICKS_FILE).is_file():
        return f"no {TICKS_FILE} (a labkit that did not record its speed loop's ticks)"
    cassettes = sorted((record.path / "cassettes").glob("*.jsonl"))
    gaps = []
    for path in cassettes:
        try:
            with path.open(encoding="utf-8") as f:
                header = json.loads(f.readline() or "{}")
        except (OSError, ValueError):
            gaps.append(f"cassettes/{path.name} has no readable header")
            continue
        if isinstance(header, dict) and header.get("format") == "labkit-frames":
            continue  # frames carry their clock readings (t_host): labkit.devices.camera.faithful
        if not isinstance(header, dict) or "clock_origin" not in header:
            gaps.append(f"cassettes/{path.name} names no clock origin (a labkit before 2026-11-27)")
    return gaps[0] if gaps else (None if cassettes else "no cassettes")


def streams_unasked(kind: str, protocol: str) -> bool:
    """Whether the driver of this device reads a stream the device sends unasked."""
    from labkit.devices.registry import driver_class
    from labkit.devices.tachometer.streaming import StreamingTachometer

    cls = driver_class(kind, protocol)
    return issubclass(cls, StreamingTachometer) or bool(getattr(cls, "talks_unasked", False))


def faithful_url(session: Path, dev: Any) -> str:
    """The ``replay://...?mode=faithful`` URL of one device's cassette."""
    path = (session / "cassettes" / f"{dev.role}.jsonl").resolve()
    flags = "&stream=1" if streams_unasked(dev.kind, dev.protocol) else ""
    flags += "&setpoints=1" if dev.kind == "motor" else ""
    return f"replay://{path}?mode=faithful{flags}"


def faithful_start(record: SessionRecord) -> float:
    """The recording's clock reading when its run began (its first event), else 0."""
    for event in record.events:
        if isinstance(event.get("t"), int | float):
            return float(event["t"])
    return 0.0


def faithful_schedules(record: SessionRecord, rig: Any) -> dict[str, list[float]]:
    """When the recording's jobs ran (clock readings): each stream reader at the reads it made
    (the cassette's ``rx`` events of its thread), the speed loop at its ticks (``clock.jsonl``)."""
    from labkit.io.cassette import CassetteReader

    schedules: dict[str, list[float]] = {}
    for role, dev in rig.devices.items():
        path = record.path / "cassettes" / f"{role}.jsonl"
        if not path.is_file() or not streams_unasked(dev.kind, dev.protocol):
            continue
        reader = CassetteReader(path)  # read as a stream: only the reads' times are kept
        origin = reader.header.get("clock_origin")
        if isinstance(origin, int | float):
            job = f"{role}-reader"
            schedules[job] = [origin + e["t"] for e in reader if e["dir"] == "rx" and e.get("th") == job]
        reader.close()
    schedules.update(recorded_ticks(record.path))
    return schedules


def _evidence_diffs(record: Any, evidence: Evidence, tolerant: frozenset[str],
                    cross: CrossVersion | None) -> list[str]:
    """The session's point events and readings files against what the replay parsed
    (:mod:`labkit.protocols.replay_evidence`; points with a protocol's image-analysis columns
    within tolerance, or within the analysis's stated accuracy for a session made by another
    version of it; readings compared as they came, only for a session that was not resumed:
    a resumed session's files also hold the first run's readings)."""
    return diff_points(evidence.points, record.point_events(), tolerant, cross) + evidence.reading_diffs()


def events_damaged(record: SessionRecord) -> bool:
    """events.jsonl had damaged lines (a crash's), skipped while reading it: a problem the reader
    reported as ``EVENTS_PATH:LINE: ...`` (a readings file of a device role named "events" is not
    it)."""
    prefix = f"{session_file(record.path, 'events.jsonl')}:"
    return any(problem.startswith(prefix) for problem in record.problems)


def replay_session(path: str | Path, sinks: list[Sink] | None = None, level: str = "auto") -> ReplayOutcome:
    """Replay a session at ``level`` (auto: exact for a virtual-clock session, faithful for a
    real-clock one) and compare it with the recording."""
    record = load_session_record(path, skip_types=REPLAY_SKIPS)
    chosen = choose_level(record, level)
    tampered = integrity_problems(record.path, record.meta)  # digests, cassette time lines
    if chosen == "analysis":
        from labkit.protocols.reanalyse import reanalyse_session

        result = reanalyse_session(load_session_record(path))
        result.differences[:0] = tampered
        result.identical = result.identical and not tampered
        if level == "auto":
            result.warnings.insert(0, f"{record.path}: a real-clock session that cannot be replayed "
                                      f"faithfully ({faithful_gap(record)}): re-analysed, not replayed")
        return result
    if not (record.path / "cassettes").is_dir():
        raise LabkitError(f"{record.path}: no cassettes to replay")
    rig = load_rig(record.rig_path())
    protocol = get_protocol(record.protocol)
    params = resolve_params(protocol.defaults, record.params, protocol.name, protocol.bounds)
    carried = [(where, p) for where, p in recorded_points(record) if "carried_points" in where]
    points, dropped = check_carried_points(carried, protocol.plan(rig, params))
    done = {int(p["step"]) for p in points}
    faithful = chosen == "faithful"
    clock = (ReplayClock(faithful_start(record), faithful_schedules(record, rig), recorded_runs(record.path),
                         site_root=RUN_SITE) if faithful else VirtualClock())
    collect = _Collect()
    evidence = Evidence(None if points or faithful else record.path / "readings", record.problems,
                        keep_readings=faithful and not points)

    def port_for(dev: Any) -> str:
        return faithful_url(record.path, dev) if faithful else replay_url(record.path, dev.role)

    pacer = [_StepPacer(clock, record)] if isinstance(clock, ReplayClock) else []
    runner = Runner(protocol, rig, params, clock=clock, sinks=[*pacer, *(sinks or []), collect, evidence],
                    previous_points=points, done_steps=done, port_override=port_for, offline=True,
                    run_id=record.run_id)
    with use_clock(clock):
        outcome = runner.run()
    if isinstance(outcome.error, CassetteError):
        raise outcome.error  # a damaged recording: nothing to compare, one line naming file:line
    outcome.reason = offline_wording(outcome.reason) or outcome.reason
    replayed = normalise(outcome.results)
    recorded = record.results
    warnings = record.problems + dropped
    replay_decisions = decisions(collect.events)  # the same steps, faults and ending, at both levels
    diffs = list(tampered)
    if faithful or not events_damaged(record):
        diffs += diff_decisions(replay_decisions, decisions(record.events))
    else:  # the bytes and results.json carry the exact level; a crash's damaged events cannot
        warnings.append(f"{record.path / 'events.jsonl'}: damaged lines, so the run's decisions were not "
                        "compared (the points and results were, with every byte)")
    cross = cross_version(protocol, record.meta)  # another version of the image analysis made it
    note = cross.note() if cross is not None else None
    if not faithful:
        tolerant = DERIVED_KEYS | analysis_keys(protocol.row)  # their last digits follow the CPU
        if recorded is None:
            diffs.append("no results.json recorded")
        elif cross is None:
            diffs += diff_results(replayed, recorded, derived_keys=tolerant)
        else:  # points within the stated accuracy; the recorded fit must follow from its points
            diffs += diff_points_then_fit(protocol, replayed, recorded,
                                          lambda a, b: diff_results(a, b, derived_keys=tolerant, cross=cross))
        diffs += _evidence_diffs(record, evidence, tolerant, cross)
        return ReplayOutcome(outcome, recorded, not diffs, diffs, warnings, "exact",
                             decisions=replay_decisions, analysis_note=note)
    if recorded is None:
        diffs.append("recording has no results.json")
    else:
        diffs += diff_points_then_fit(protocol, replayed, recorded,
                                      lambda a, b: diff_within(a, b, cross=cross))
    if not points:  # a resumed session's readings files also hold the first run's readings
        diffs += faithful_reading_diffs(record, rig, evidence.parsed)
    ports = [port.report() for port in runner.ports.values() if hasattr(port, "report")]
    return ReplayOutcome(outcome, recorded, not diffs, diffs, warnings, "faithful", ports, replay_decisions,
                         dict(clock.repeated) if isinstance(clock, ReplayClock) else {}, analysis_note=note)
