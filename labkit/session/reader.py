"""Reading a session back (complete, or cut short by a crash) for resume, replay and analysis."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from labkit.session.export import read_jsonl
from labkit.session.writer import SessionError


@dataclass
class SessionRecord:
    path: Path
    meta: dict[str, Any]
    events: list[dict[str, Any]]
    results: dict[str, Any] | None

    @property
    def protocol(self) -> str:
        return str(self.meta["protocol"])

    @property
    def params(self) -> dict[str, Any]:
        return dict(self.meta.get("params") or {})

    def rig_path(self) -> Path:
        return self.path / str(self.meta.get("rig_file", "rig.toml"))

    def completed_points(self) -> list[dict[str, Any]]:
        """Result rows of the steps this session (and the sessions it resumed) finished."""
        return [e["point"] for e in self.events if e.get("type") == "point"]

    def readings(self, role: str) -> list[dict[str, Any]]:
        path = self.path / "readings" / f"{role}.jsonl"
        return read_jsonl(path) if path.exists() else []


def load_session(path: str | Path) -> SessionRecord:
    """Read ``run.json``, ``events.jsonl`` and ``results.json`` (if any). Raises SessionError."""
    p = Path(path)
    run = p / "run.json"
    if not run.is_file():
        raise SessionError(f"{p}: not a labkit session (no run.json)")
    try:
        meta = json.loads(run.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise SessionError(f"{run}: unreadable: {exc}") from None
    for key in ("protocol", "params"):
        if key not in meta:
            raise SessionError(f"{run}: missing key {key!r}")
    events_path = p / "events.jsonl"
    events = read_jsonl(events_path) if events_path.exists() else []
    results = None
    if (p / "results.json").is_file():
        try:
            results = json.loads((p / "results.json").read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise SessionError(f"{p / 'results.json'}: unreadable: {exc}") from None
    return SessionRecord(p, meta, events, results)
