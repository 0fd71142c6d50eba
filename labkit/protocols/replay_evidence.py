"""What an exact replay checks besides ``results.json`` (issue 27, *sessions you can trust*):
the points in ``events.jsonl`` and the readings in ``readings/ROLE.jsonl`` are what the
cassettes' bytes give. A session whose reading or point was edited by hand (a force x10, a
balance file doubled) replays to the same results.json only if that was edited too; these
checks name the file and line that no longer follows from the recorded bytes.

Only for the exact level (virtual-clock sessions, every byte in its recorded order): there a
replay reproduces every reading and point bit for bit. A faithful replay's readings fall at
slightly other times; its points are compared within tolerances by
:mod:`labkit.protocols.replay_compare`.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from labkit.protocols.replay_compare import ADDED_KEYS, close_enough
from labkit.readings import declared

if TYPE_CHECKING:
    from labkit.protocols.analysis_versions import CrossVersion

#: the reading keys compared (the time, the number and the bytes it came from)
READING_KEYS = ("t", "value", "raw")
#: at most this many differences are listed per file
MAX_LISTED = 5


class Evidence:
    """Sink keeping the replay's points, and comparing each reading the replay parses with the
    recorded one of the same device as it comes (:class:`ReadingsCheck`; ``readings_dir`` None:
    readings not compared), so memory does not grow with the readings. ``keep_readings``: also
    keep, by device, the value and unit parsed from each reading's raw bytes (``parsed``), for a
    faithful replay's check against the cassettes
    (:func:`labkit.protocols.reading_evidence.faithful_reading_diffs`)."""

    def __init__(self, readings_dir: Path | None = None, problems: list[str] | None = None,
                 keep_readings: bool = False) -> None:
        self.points: list[dict[str, Any]] = []
        self.readings_dir = readings_dir
        self.problems = problems
        self.checks: dict[str, ReadingsCheck] = {}
        self.keep_readings = keep_readings
        self.parsed: dict[str, dict[str, tuple[Any, Any]]] = {}

    def on_event(self, event: Any) -> None:
        kind = event.get("type")
        if kind == "point":
            self.points.append(json.loads(json.dumps(event.get("point"))))  # as events.jsonl holds it
        elif kind == "reading":
            parsed = event.reading.as_json()   # with its quantity and unit
            if self.readings_dir is not None:
                self._check(str(event.get("device"))).add(parsed)
            if self.keep_readings:
                by_raw = self.parsed.setdefault(str(event.get("device")), {})
                by_raw[str(parsed.get("raw"))] = (parsed.get("value"), parsed.get("unit"))

    def _check(self, device: str) -> ReadingsCheck:
        check = self.checks.get(device)
        if check is None:
            assert self.readings_dir is not None
            check = self.checks[device] = ReadingsCheck(device, self.readings_dir, self.problems)
        return check

    def reading_diffs(self) -> list[str]:
        """Every device's differences (also a readings file of a device that gave none)."""
        if self.readings_dir is None:
            return []
        out: list[str] = []
        for device in sorted(set(self.checks) | {p.stem for p in self.readings_dir.glob("*.jsonl")}):
            out += self._check(device).finish()
        return out


class ReadingsCheck:
    """One device's readings file (``readings/DEVICE.jsonl``) against the readings the replay
    parsed from its bytes, compared one by one as they come; what :func:`diff_readings` says."""

    def __init__(self, device: str, readings_dir: Path, problems: list[str] | None) -> None:
        from labkit.session.paths import session_file
        from labkit.session.reader import iter_jsonl_lines

        self.device = device
        path = readings_dir / f"{device}.jsonl"
        self.file = str(path)
        self._recorded: Iterator[tuple[int, dict[str, Any]]] = (
            declared(iter_jsonl_lines(session_file(readings_dir.parent, "readings", path.name), problems))
            if path.exists() else iter(()))
        self.replayed = 0
        self.recorded = 0
        self.lines: list[str] = []   # at most MAX_LISTED differences, in order

    def add(self, again: dict[str, Any]) -> None:
        self.replayed += 1
        row = next(self._recorded, None)
        if row is None:
            return
        self.recorded += 1
        if len(self.lines) < MAX_LISTED:
            self.lines += _reading_difference(self.file, self.recorded, row[1], again)

    def finish(self) -> list[str]:
        self.recorded += sum(1 for _ in self._recorded)
        out = []
        if self.replayed != self.recorded:
            out.append(f"{self.file}: {self.recorded} readings recorded, the cassette of {self.device} "
                       f"gives {self.replayed}")
        for line in self.lines:
            out.append(line)
            if len(out) >= MAX_LISTED:
                out.append(f"{self.file}: further differences not listed")
                break
        return out


def _reading_difference(file: str, line: int, rec: dict[str, Any], again: dict[str, Any]) -> list[str]:
    keys = [k for k in READING_KEYS if not _same(rec.get(k), again.get(k))]
    if not keys:
        return []
    shown = ", ".join(f"{k} recorded {rec.get(k)!r}, from the bytes {again.get(k)!r}" for k in keys)
    return [f"{file}:{line}: this reading does not follow from the cassette ({shown}): edited?"]


def _same(a: Any, b: Any, tolerant: bool = False) -> bool:
    if tolerant and isinstance(a, int | float) and isinstance(b, int | float) \
            and not isinstance(a, bool) and not isinstance(b, bool):
        return close_enough(float(a), float(b))
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def diff_points(replayed: list[dict[str, Any]], recorded: list[tuple[str, Any]],
                tolerant: frozenset[str] = frozenset(), cross: CrossVersion | None = None) -> list[str]:
    """Each recorded point event (``events.jsonl:LINE``) against the replay's point of the same
    step; keys in ``tolerant`` (a protocol's image-analysis columns) compared within
    :data:`~labkit.protocols.replay_compare.REPLAY_FIT_RTOL`. A point line that is damaged or
    missing is the session reader's warning already; a step the replay makes and the events do
    not hold is results.json's difference."""
    out = []
    by_step = {p.get("step"): p for p in replayed}
    for where, point in recorded:
        if not isinstance(point, dict) or point.get("step") not in by_step:
            continue
        again = by_step[point["step"]]
        keys = sorted(k for k in set(point) | set(again)
                      if not (cross.agrees(k, again.get(k), point.get(k), again, point)
                              if cross is not None and k in cross.accuracy
                              else _same(point.get(k), again.get(k), k in tolerant))
                      and not (k not in point and k in ADDED_KEYS))  # a key newer than the recording
        if not keys:
            continue
        shown = ", ".join(f"{k} recorded {point.get(k)!r}, from the bytes {again.get(k)!r}" for k in keys[:3])
        out.append(f"{where}: this point does not follow from the cassettes ({shown}): edited?")
        if len(out) >= MAX_LISTED:
            break
    return out


def diff_readings(device: str, replayed: list[dict[str, Any]], recorded: list[dict[str, Any]],
                  file: str) -> list[str]:
    """A device's recorded readings file against the readings the replay parsed from its bytes."""
    out = []
    if len(replayed) != len(recorded):
        out.append(f"{file}: {len(recorded)} readings recorded, the cassette of {device} gives "
                   f"{len(replayed)}")
    for line, (rec, again) in enumerate(zip(recorded, replayed, strict=False), start=1):
        found = _reading_difference(file, line, rec, again)
        if found:
            out += found
            if len(out) >= MAX_LISTED:
                out.append(f"{file}: further differences not listed")
                break
    return out
