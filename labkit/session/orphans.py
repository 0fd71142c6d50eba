"""Close the session of a run whose process died without closing it (docs/explanation/safety.md).

When the worker of a supervised ``labkit run`` is killed (SIGKILL, the OOM killer, a crashed
interpreter), its ``run.json`` still says ``"status": "running"``. The supervisor, after it has
stopped the motors, finds that session by the worker's PID (``run.json`` key ``pid``) and
records ``"status": "killed"`` with the reason and the end time. The files written before the
kill stay as they are, so the session can still be resumed.

A PID is reused once its process is gone: a session left ``running`` by a run killed long ago
(no supervisor then, or a reboot) may name the PID of today's worker. So a session is this
worker's only if it names the worker's *process identity* too (``pid_start`` in run.json: the
boot and the process's start time, :func:`process_identity`), and, for sessions written before
that key, only if it started after the worker was forked.
"""

from __future__ import annotations

import datetime as _dt
import json
from pathlib import Path

from labkit.session.writer import utc_now, write_json_atomic

KILLED = "killed"


#: a session's ``started`` (whole seconds) may read up to this much before the fork it followed
STARTED_SLACK_S = 2.0


def _started_before(meta: dict, since: float) -> bool:
    try:
        started = _dt.datetime.fromisoformat(str(meta.get("started"))).timestamp()
    except ValueError:
        return False  # no readable start: the PID (and identity, if any) decide
    return started < since - STARTED_SLACK_S


def running_sessions_of(root: str | Path, pid: int, identity: str | None = None,
                        since: float | None = None) -> list[tuple[Path, dict]]:
    """``(folder, run.json contents)`` of the sessions under ``root`` whose run.json says
    ``running`` with process ``pid``; with ``identity`` (:func:`process_identity` of the worker)
    not those naming another process of that PID; with ``since`` (the time the worker was
    forked) not those started before it."""
    found = []
    for meta_path in sorted(Path(root).glob("*/run.json")):
        try:
            meta = json.loads(meta_path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue  # not a session this process wrote, or unreadable: leave it alone
        if not (isinstance(meta, dict) and meta.get("status") == "running" and meta.get("pid") == pid):
            continue
        if identity is not None and meta.get("pid_start") not in (None, identity):
            continue  # the PID was another process's: a run that died long ago
        if since is not None and _started_before(meta, since):
            continue
        found.append((meta_path.parent, meta))
    return found


def close_killed_sessions(root: str | Path, pid: int, reason: str, identity: str | None = None,
                          since: float | None = None) -> list[Path]:
    """Mark the sessions of dead process ``pid`` as ``killed`` with ``reason``; their paths
    (``identity``, ``since``: :func:`running_sessions_of`).

    A session whose run.json cannot be rewritten (full disk) keeps ``running``: the reason is
    then only on the terminal, and the session is resumable either way."""
    closed = []
    for session, meta in running_sessions_of(root, pid, identity, since):
        meta.update(status=KILLED, reason=reason, ended=utc_now())
        try:
            write_json_atomic(session / "run.json", meta)
        except OSError:
            continue
        closed.append(session)
    return closed
