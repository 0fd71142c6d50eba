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
from typing import Any

from labkit.protocols.replay_compare import ADDED_KEYS, close_enough

#: the reading keys compared (the time, the number and the bytes it came from)
READING_KEYS = ("t", "value", "raw")
#: at most this many differences are listed per file
MAX_LISTED = 5


class Evidence:
    """Sink keeping the replay's points and readings (by device)."""

    def __init__(self) -> None:
        self.points: list[dict[str, Any]] = []
        self.readings: dict[str, list[dict[str, Any]]] = {}

    def on_event(self, event: Any) -> None:
        kind = event.get("type")
        if kind == "point":
            self.points.append(json.loads(json.dumps(event.get("point"))))  # as events.jsonl holds it
        elif kind == "reading":
            self.readings.setdefault(str(event.get("device")), []).append(event.to_json())


def _same(a: Any, b: Any, tolerant: bool = False) -> bool:
    if tolerant and isinstance(a, int | float) and isinstance(b, int | float) \
            and not isinstance(a, bool) and not isinstance(b, bool):
        return close_enough(float(a), float(b))
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def diff_points(replayed: list[dict[str, Any]], recorded: list[tuple[str, Any]],
                tolerant: frozenset[str] = frozenset()) -> list[str]:
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
                      if not _same(point.get(k), again.get(k), k in tolerant)
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
        keys = [k for k in READING_KEYS if not _same(rec.get(k), again.get(k))]
        if keys:
            shown = ", ".join(f"{k} recorded {rec.get(k)!r}, from the bytes {again.get(k)!r}" for k in keys)
            out.append(f"{file}:{line}: this reading does not follow from the cassette ({shown}): edited?")
            if len(out) >= MAX_LISTED:
                out.append(f"{file}: further differences not listed")
                break
    return out
