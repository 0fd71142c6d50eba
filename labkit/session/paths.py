"""Paths inside a session directory, checked: nothing a session writes or reads lies outside it.

A device role becomes a file name (``readings/ROLE.jsonl``, ``cassettes/ROLE.jsonl``) and a
session's run.json names its rig copy (``rig_file``). A role such as ``../../other/S/events``
or ``/tmp/x``, or a downloaded session whose run.json says ``"rig_file": "../../x"``, would
otherwise reach files of another session or anywhere on the disk.
"""

from __future__ import annotations

from pathlib import Path

from labkit.errors import SessionError


def session_file(session: str | Path, *parts: str) -> Path:
    """``session/part/...`` resolved; SessionError unless it lies inside ``session``.

    Each part must be one plain name (no ``/``, ``\\``, ``..`` or absolute path)."""
    root = Path(session).resolve()
    for part in parts:
        if not part or part in (".", "..") or "/" in part or "\\" in part or "\x00" in part:
            raise SessionError(f"{session}: {part!r} leads outside the session (not a plain file name)")
    path = root.joinpath(*parts).resolve()
    if path != root and root not in path.parents:
        raise SessionError(f"{session}: {'/'.join(parts)!r} leads outside the session (to {path})")
    return path
