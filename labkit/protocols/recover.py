"""A session whose ``results.json`` is missing (issue 27): lost, deleted, or never written (the
run was killed after its last point). Its results are in ``events.jsonl`` still:

* the ``results`` event the run emitted as it ended (the very document results.json holds), or
* when the run ended before that, the ``point`` events (and run.json's ``carried_points``),
  fitted again with the protocol's quick fit, as the run would have at its end.

``labkit report`` and ``labkit fit`` then use them, saying so on stderr; ``labkit run --resume``
of such a session with every step done says what is missing and what to run instead.
"""

from __future__ import annotations

from typing import Any

from labkit.session import SessionRecord


def results_from_events(record: SessionRecord) -> tuple[dict[str, Any], str] | None:
    """The session's results and where they come from (``events.jsonl:LINE`` or the words
    "recomputed from ..."); None when events.jsonl holds no point."""
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
    return _refit(record, points), (f"recomputed from the {len(points)} points in events.jsonl and run.json "
                                    "(the protocol's quick fit)")


def _refit(record: SessionRecord, points: list[dict[str, Any]]) -> dict[str, Any]:
    from labkit.protocols import get_protocol
    from labkit.protocols.params import resolve_params
    from labkit.protocols.runner import normalise
    from labkit.rig import load_rig

    protocol = get_protocol(record.protocol)
    params = resolve_params(protocol.defaults, record.params, protocol.name)
    protocol.plan(load_rig(record.rig_path()), params)  # what the fit needs from the parameters
    try:
        fit = protocol.fit(points)
    except Exception as exc:  # noqa: BLE001 - as the runner records a failed quick fit
        fit = {"model": getattr(protocol, "fit_model", "unknown"), "params": {},
               "error": f"{type(exc).__name__}: {exc}"}
    return normalise({"protocol": protocol.name, "points": points, "fit": fit})
