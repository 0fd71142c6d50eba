"""Close the session of a run whose process died without closing it (docs/explanation/safety.md).

When the worker of a supervised ``labkit run`` is killed (SIGKILL, the OOM killer, a crashed
interpreter), its ``run.json`` still says ``"status": "running"``. The supervisor, after it has
stopped the motors, finds that session by the worker's PID (``run.json`` key ``pid``) and
records ``"status": "killed"`` with the reason and the end time. The files written before the
kill stay as they are, so the session can still be resumed.
"""

from __future__ import annotations

import json
from pathlib import Path

from labkit.session.writer import utc_now, write_json_atomic

KILLED = "killed"


def running_sessions_of(root: str | Path, pid: int) -> list[tuple[Path, dict]]:
    """``(folder, run.json contents)`` of the sessions under ``root`` whose run.json says
    ``running`` with process ``pid``."""
    found = []
    for meta_path in sorted(Path(root).glob("*/run.json")):
        try:
            meta = json.loads(meta_path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue  # not a session this process wrote, or unreadable: leave it alone
        if isinstance(meta, dict) and meta.get("status") == "running" and meta.get("pid") == pid:
            found.append((meta_path.parent, meta))
    return found


def close_killed_sessions(root: str | Path, pid: int, reason: str) -> list[Path]:
    """Mark the sessions of dead process ``pid`` as ``killed`` with ``reason``; their paths.

    A session whose run.json cannot be rewritten (full disk) keeps ``running``: the reason is
    then only on the terminal, and the session is resumable either way."""
    closed = []
    for session, meta in running_sessions_of(root, pid):
        meta.update(status=KILLED, reason=reason, ended=utc_now())
        try:
            write_json_atomic(session / "run.json", meta)
        except OSError:
            continue
        closed.append(session)
    return closed
