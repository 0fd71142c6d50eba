"""A session whose ``results.json`` is missing (issue 27): lost, deleted, or never written (the
run was killed after its last point). Its results are in ``events.jsonl`` still:

* the ``results`` event the run emitted as it ended (the very document results.json holds), or
* when the run ended before that, its ``point`` events (with run.json's ``carried_points``),
  without the protocol's quick fit (``labkit fit`` and ``labkit report`` make their own).

``labkit report`` and ``labkit fit`` then use them, saying so on stderr; ``labkit run --resume``
of such a session with every step done says what is missing and what to run instead.
"""

from __future__ import annotations

from typing import Any

from labkit.session.reader import SessionRecord


def results_from_events(record: SessionRecord) -> tuple[dict[str, Any], str] | None:
    """The session's results and where they come from (``the results event at
    events.jsonl:LINE`` or ``the N points ...``); None when events.jsonl holds no point."""
    lines = record.event_lines or [0] * len(record.events)
    for number, event in reversed(list(zip(lines, record.events, strict=True))):
        if event.get("type") == "results" and isinstance(event.get("results"), dict) \
                and isinstance(event["results"].get("points"), list):
            return event["results"], f"the results event at {record.path / 'events.jsonl'}:{number}"
    carried = record.meta.get("carried_points")
    points = [p for p in (carried if isinstance(carried, list) else []) if isinstance(p, dict)]
    points += [p for _, p in record.point_events() if isinstance(p, dict)]
    if not points:
        return None
    return ({"protocol": record.meta.get("protocol"), "points": points},
            f"the {len(points)} points in events.jsonl and run.json (the run ended before its results "
            "and quick fit)")
