"""``labkit replay --analysis-only``: a session's numbers again, from its recorded bytes, with no
protocol run (docs/explanation/replay.md). Works for any session, also one recorded by an older labkit or on
a rig whose timing cannot be replayed.

1. Every reading a session kept (``readings/ROLE.jsonl``: its time and the raw bytes it was
   parsed from) is parsed again by today's parser of its device's protocol
   (:data:`REPARSERS`); a value that now comes out otherwise is reported.
2. The points are computed again from the re-parsed readings, the frame cassette and the run's
   recorded decisions (``events.jsonl``), each by its protocol's own rule
   (``ProtocolDef.reanalyse_step``, given a :class:`labkit.protocols.reanalysis.RecordedRun`):
   speed-sweep averages each step's balance and tachometer readings over the recorded
   averaging window (``settled`` to the rotor's stop) with the rest readings around it;
   spin-critical takes each step's recorded drops (rotor speed and spin at the drop, as
   registered) through the protocol's consistency rule; cone-sweep and strobe-sweep analyse
   each step's bursts again from the frame cassette (strobe-sweep with the strobe's status
   lines from ``readings/strobe.jsonl``). A protocol without a rule has its points taken as
   recorded, and the replay says so.
3. The protocol's quick fit is made again from those points.

The result is compared with ``results.json`` within the faithful tolerances
(:mod:`labkit.protocols.replay_compare`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from labkit.devices.balance.mtsics import parse_weight
from labkit.devices.strobe.protocol import parse_status_line
from labkit.devices.strobe.protocol import strip_junk as strip_strobe_junk
from labkit.devices.tachometer.labkit_tach import parse_tach_sample, strip_junk
from labkit.protocols.analysis_versions import cross_version, diff_points_then_fit
from labkit.protocols.params import resolve_params
from labkit.protocols.reanalysis import Parsed, RecordedRun, point_event
from labkit.protocols.registry import get_protocol
from labkit.protocols.replay_compare import ReplayOutcome, diff_within
from labkit.protocols.runner import RunOutcome, fit_or_error, normalise
from labkit.rig import load_rig
from labkit.session import SessionRecord
from labkit.units import rpm_to_rad_s, to_si


def _mtsics(t: float, raw: bytes) -> Parsed:
    weight = parse_weight(raw)
    if weight.value is None or weight.unit is None:
        return Parsed(t, math.nan, "kg", False, overload=True)
    _, value, unit = to_si(weight.value, weight.unit)
    return Parsed(t, value, unit, weight.status == "S")


def _labkit_tach(t: float, raw: bytes) -> Parsed:
    sample = parse_tach_sample(strip_junk(raw.strip()))
    if "over_range" in sample.flags:
        return Parsed(t, math.nan, "rad/s", False, overload=True)
    return Parsed(t, rpm_to_rad_s(sample.rpm), "rad/s", "noisy" not in sample.flags)


def _labkit_strobe(t: float, raw: bytes) -> Parsed:
    status = parse_status_line(strip_strobe_junk(raw.strip()), t)
    return Parsed(t, status.strobe_hz, "Hz", status.locked)


#: protocol -> parser of one recorded frame (its ``raw`` bytes) into a reading
REPARSERS: dict[str, Callable[[float, bytes], Parsed]] = {
    "mtsics": _mtsics, "labkit_tach": _labkit_tach, "labkit_strobe": _labkit_strobe}


def reparse(record: SessionRecord, rig: Any, notes: list[str]) -> dict[str, list[Parsed]]:
    """Every kept reading of every device parsed again (as recorded where no parser is known)."""
    out: dict[str, list[Parsed]] = {}
    for role, dev in rig.devices.items():
        rows = record.readings(role)
        parser = REPARSERS.get(dev.protocol)
        if parser is None:
            if rows:
                notes.append(f"{role}: no re-parser for protocol {dev.protocol!r}; its readings as recorded")
            out[role] = [Parsed(r["t"], _num(r.get("value")), r.get("unit", ""), bool(r.get("stable", True)),
                                bool(r.get("overload", False))) for r in rows]
            continue
        parsed, changed = [], 0
        for row in rows:
            try:
                reading = parser(float(row["t"]), str(row.get("raw", "")).encode("latin-1"))
            except (ValueError, KeyError) as exc:
                notes.append(f"{role}: {row.get('raw')!r} at {row.get('t')} no longer parses ({exc})")
                continue
            if not _same(reading.value, _num(row.get("value"))):
                changed += 1
            parsed.append(reading)
        if changed:
            notes.append(f"{role}: {changed} of {len(rows)} readings parse to another value than recorded")
        out[role] = parsed
    return out


def _num(value: Any) -> float:
    return float(value) if isinstance(value, int | float) else math.nan


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)


def _by_step(events: list[dict[str, Any]]) -> dict[int, list[dict[str, Any]]]:
    steps: dict[int, list[dict[str, Any]]] = {}
    current: int | None = None
    for event in events:
        if event.get("type") == "step":
            current = int(event["index"])
        if current is not None:
            steps.setdefault(current, []).append(event)
    return steps


def reanalyse_session(record: SessionRecord) -> Any:
    """The analysis-only level (module docstring); a
    :class:`labkit.protocols.replay_compare.ReplayOutcome`."""

    rig = load_rig(record.rig_path())
    protocol = get_protocol(record.protocol)
    params = resolve_params(protocol.defaults, record.params, protocol.name)
    notes: list[str] = []
    run = RecordedRun(record, rig, params, reparse(record, rig, notes), notes)
    steps = sorted(_by_step(record.events).items())
    try:
        points = [p for step, events in steps
                  if (p := protocol.reanalyse_step(run, step, events)) is not None]
        why_not = None
    except NotImplementedError as exc:  # no rule, or none for this session: why the points stand
        points = [p for _, events in steps if (p := point_event(events)) is not None]
        why_not = str(exc) or f"no analysis-only rule for protocol {protocol.name!r}"
    points = list(record.meta.get("carried_points") or []) + points
    protocol.plan(rig, params)  # sets what the fit needs from the parameters (e.g. w_ref)
    results = normalise({"protocol": protocol.name, "points": points, "fit": fit_or_error(protocol, points)})
    recorded = record.results
    cross = cross_version(protocol, record.meta) if why_not is None else None
    if recorded is None:
        diffs = ["no results.json recorded"]
    elif cross is None:
        diffs = diff_within(results, recorded)
    else:  # another version of the image analysis: its numbers within its stated accuracy
        diffs = diff_points_then_fit(protocol, results, recorded, lambda a, b: diff_within(a, b, cross=cross))
    outcome = RunOutcome("completed", None, record.path, results)
    if why_not is not None:
        notes.append(f"{why_not}: the points of {protocol.name} are taken as recorded, only the fit is "
                     "recomputed from them")
    note = cross.note() if cross is not None else None
    return ReplayOutcome(outcome, recorded, not diffs, diffs, record.problems + notes, "analysis",
                         recomputed=why_not is None, analysis_note=note)
