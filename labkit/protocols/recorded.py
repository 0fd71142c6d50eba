"""What a recorded session offers a resumed run and a replay: the points it holds, each with
where it was recorded, and the ``replay://`` URL of each device's cassette."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from labkit.session import SessionRecord


def recorded_points(record: SessionRecord) -> list[tuple[str, Any]]:
    """``(where, point)`` of every point a session holds (``run.json:carried_points[i]`` and
    ``events.jsonl:LINE``), for :func:`labkit.protocols.resume.check_carried_points`."""
    carried = record.meta.get("carried_points") or []
    if not isinstance(carried, list):
        carried = [carried]
    run_json = record.path / "run.json"
    return [(f"{run_json}:carried_points[{i}]", p) for i, p in enumerate(carried)] + record.point_events()


def replay_url(session: Path, role: str) -> str:
    """The ``replay://`` URL of one device's cassette in a session (timed, strict)."""
    return f"replay://{(session / 'cassettes' / f'{role}.jsonl').resolve()}?mode=timed"
