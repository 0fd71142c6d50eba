"""``labkit replay --analysis-only``: a session's numbers again, from its recorded bytes, with no
protocol run (docs/explanation/replay.md). Works for any session, also one recorded by an older labkit or on
a rig whose timing cannot be replayed.

1. Every reading a session kept (``readings/ROLE.jsonl``: its time and the raw bytes it was
   parsed from) is parsed again by today's parser of its device's protocol
   (:data:`REPARSERS`); a value that now comes out otherwise is reported.
2. The points are computed again from the re-parsed readings and the run's recorded
   decisions (``events.jsonl``): speed-sweep averages each step's balance and tachometer
   readings over the recorded averaging window (``settled`` to the rotor's stop) with the
   rest readings around it; spin-critical takes each step's recorded drops (rotor speed and
   spin at the drop, as registered) through the protocol's consistency rule.
   cone-sweep analyses each step's burst again from the frame cassette
   (:mod:`labkit.protocols.reanalyse_camera`); strobe-sweep has no rule yet (its points are
   taken as recorded, and the replay says so).
3. The protocol's quick fit is made again from those points.

The result is compared with ``results.json`` within the faithful tolerances
(:mod:`labkit.protocols.replay_compare`).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from labkit.devices.balance.mtsics import parse_weight
from labkit.devices.tachometer.labkit_tach import parse_tach_sample, strip_junk
from labkit.protocols.params import resolve_params
from labkit.protocols.registry import get_protocol
from labkit.protocols.replay_compare import ReplayOutcome, diff_within
from labkit.protocols.runner import RunOutcome, normalise
from labkit.protocols.speed_sweep import drift_warnings, finite_std, mean_stderr, reading_force_n
from labkit.protocols.spin_critical import point_from_trials
from labkit.rig import load_rig
from labkit.session import SessionRecord
from labkit.units import n_to_gf, rad_s_to_rpm, rpm_to_rad_s, to_si


@dataclass(frozen=True)
class Parsed:
    """A re-parsed reading: what the protocols use of a :class:`~labkit.readings.Reading`."""

    t: float
    value: float
    unit: str
    stable: bool
    overload: bool = False


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


#: protocol -> parser of one recorded frame (its ``raw`` bytes) into a reading
REPARSERS: dict[str, Callable[[float, bytes], Parsed]] = {"mtsics": _mtsics, "labkit_tach": _labkit_tach}


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


def _sweep_point(step: int, events: list[dict[str, Any]], readings: dict[str, list[Parsed]],
                 params: dict[str, Any]) -> dict[str, Any] | None:
    """One speed-sweep point from its recorded window (speed_sweep.SpeedSweep.run_step)."""
    settled = next((e for e in events if e["type"] == "settled"), None)
    point = next((e for e in events if e["type"] == "point"), None)
    targets = [e for e in events if e["type"] == "setpoint"]
    if settled is None or point is None:
        return None
    t_start = settled["t"]
    stop = next((e["t"] for e in targets if e["t"] > t_start and e["target_rad_s"] == 0.0), point["t"])
    t_end = min(stop, point["t"])
    balance = readings["balance"]
    at_speed = [r for r in balance if t_start < r.t <= t_end]
    speeds = [r.value for r in readings["rotor_tach"] if t_start < r.t <= t_end]
    drift, rests_g = 0.0, None
    if params["zero"] == "each":
        go = next((e["t"] for e in targets if e["target_rad_s"] > 0), t_start)
        before = [r for r in balance if r.t <= go and r.t >= events[0]["t"]]
        after = [r for r in balance if t_end < r.t <= point["t"]]
        if before and after:
            r0, r1 = before[-1], after[-1]
            t_mid = 0.5 * (at_speed[0].t + at_speed[-1].t) if at_speed else t_start
            frac = (t_mid - r0.t) / (r1.t - r0.t) if r1.t > r0.t else 0.5
            drift = reading_force_n(r0) + frac * (reading_force_n(r1) - reading_force_n(r0))
            rests_g = (n_to_gf(reading_force_n(r0)), n_to_gf(reading_force_n(r1)))
    force, stderr = mean_stderr([reading_force_n(r) - drift for r in at_speed])
    finite = [v for v in speeds if math.isfinite(v)]
    speed = statistics.fmean(finite) if finite else math.nan
    data = point["point"]
    return {"step": step, "direction": data.get("direction"), "repeat": data.get("repeat"),
            "target_rpm": data.get("target_rpm"), "speed_rad_s": speed, "speed_rpm": rad_s_to_rpm(speed),
            "speed_std_rpm": rad_s_to_rpm(finite_std(speeds)), "force_n": force, "force_g": n_to_gf(force),
            "force_stderr_n": stderr, "force_stderr_g": n_to_gf(stderr), "n": len(at_speed),
            "settle_time_s": settled["settle_time_s"], "drift_n": drift,
            "drift_g": n_to_gf(drift) if rests_g else None,
            "unstable": sum(1 for r in at_speed if not r.stable),
            "warnings": drift_warnings(n_to_gf(force), n_to_gf(drift), rests_g,
                                       float(params.get("drift_warn", 0.05)))}


def _spin_point(step: int, events: list[dict[str, Any]], params: dict[str, Any]) -> dict[str, Any] | None:
    """One spin-critical point from its recorded drops (spin_critical.SpinCritical.run_step's rule)."""
    point = next((e for e in events if e["type"] == "point"), None)
    if point is None:
        return None
    trials = [{k: e[k] for k in ("rotor_rad_s", "spin_rad_s", "cause", "hold_s")}
              for e in events if e["type"] == "drop"]
    n = int(params["consistent_n"])
    consistent = False
    for i in range(len(trials)):
        recent = [t["spin_rad_s"] for t in trials[: i + 1][-n:]]
        spread = (max(recent) - min(recent)) / max(abs(statistics.fmean(recent)), 1e-9) * 100.0
        if len(recent) >= n and spread <= params["consistency_pct"]:
            consistent = True
            break
    return {"step": step, **point_from_trials(point["point"].get("target_rpm"), trials, consistent, n)}


def reanalyse_session(record: SessionRecord) -> Any:
    """The analysis-only level (module docstring); a
    :class:`labkit.protocols.replay_compare.ReplayOutcome`."""

    rig = load_rig(record.rig_path())
    protocol = get_protocol(record.protocol)
    params = resolve_params(protocol.defaults, record.params, protocol.name)
    notes: list[str] = []
    readings = reparse(record, rig, notes)
    carried = list(record.meta.get("carried_points") or [])
    points = list(carried)
    bursts = None
    if protocol.name == "cone-sweep":
        from labkit.protocols.reanalyse_camera import ConeBursts

        bursts = ConeBursts(record)
    for step, events in sorted(_by_step(record.events).items()):
        recorded_point = next((e["point"] for e in events if e["type"] == "point"), None)
        if protocol.name == "speed-sweep":
            point = _sweep_point(step, events, readings, params)
        elif protocol.name == "spin-critical":
            point = _spin_point(step, events, params)
        elif bursts is not None and isinstance(recorded_point, dict):
            point = bursts.point(step, recorded_point, params)
        else:
            point = recorded_point
        if point is not None:
            points.append(point)
    protocol.plan(rig, params)  # sets what the fit needs from the parameters (e.g. w_ref)
    try:
        fit = protocol.fit(points)
    except Exception as exc:  # noqa: BLE001 - as the runner records a failed quick fit
        fit = {"model": getattr(protocol, "fit_model", "unknown"), "params": {},
               "error": f"{type(exc).__name__}: {exc}"}
    results = normalise({"protocol": protocol.name, "points": points, "fit": fit})
    recorded = record.results
    diffs = diff_within(results, recorded) if recorded is not None else ["no results.json recorded"]
    outcome = RunOutcome("completed", None, record.path, results)
    recomputed = protocol.name in ("speed-sweep", "spin-critical", "cone-sweep")
    if not recomputed:
        notes.append(f"no analysis-only rule for protocol {protocol.name!r}: its points are taken as "
                     "recorded, only the fit is recomputed from them")
    return ReplayOutcome(outcome, recorded, not diffs, diffs, record.problems + notes, "analysis",
                         recomputed=recomputed)
