"""Edits a tamperer (or a slip of the hand) makes to a copied session, for the tests that check
`labkit replay` names them."""

from __future__ import annotations

import json
from pathlib import Path


def without_digests(session: Path) -> None:
    """As a session from before digests, or one whose editor fixed run.json too: only the
    analysis rule can then see an edit."""
    meta = json.loads((session / "run.json").read_text())
    meta.pop("digests", None)
    (session / "run.json").write_text(json.dumps(meta))


def scale_point(session: Path, step: int, key: str, factor: float) -> None:
    """Multiply ``key`` of step ``step``'s point by ``factor`` in results.json and in its point
    event, consistently (not what the recorded bytes give)."""
    results = json.loads((session / "results.json").read_text())
    point, = (p for p in results["points"] if p.get("step") == step)
    point[key] *= factor
    (session / "results.json").write_text(json.dumps(results))
    events = [json.loads(line) for line in (session / "events.jsonl").read_text().splitlines()]
    for event in events:
        if event.get("type") == "point" and event["point"].get("step") == step:
            event["point"][key] = point[key]
    (session / "events.jsonl").write_text("".join(json.dumps(e) + "\n" for e in events))

