"""Child processes a test starts, ended with everything they started in turn.

``subprocess.Popen.terminate()`` ends only the process it started: ``python -m rerun`` is a
wrapper that runs the ``rerun`` binary as its own child, which then outlives the test,
reparented to init. :func:`start_group` starts the child in a new process group
(``start_new_session``) and :func:`stop_group` ends the whole group: SIGTERM, then SIGKILL
for whatever is still there after ``timeout_s``.

:func:`processes_with_env` finds processes by an environment marker (children inherit the
environment even when orphaned); ``tests/conftest.py`` uses it to fail a test session that
leaves a process behind.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Any


def start_group(args: list[str], **popen: Any) -> subprocess.Popen:
    """``Popen(args, **popen)`` as the leader of a new process group."""
    return subprocess.Popen(args, start_new_session=True, **popen)


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def stop_group(proc: subprocess.Popen, timeout_s: float = 10.0) -> None:
    """End ``proc`` and every process of its group (SIGTERM; SIGKILL after ``timeout_s``)."""
    pgid = proc.pid
    for sig in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(pgid, sig)
        except ProcessLookupError:
            pass
        deadline = time.monotonic() + timeout_s
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            continue
        while _group_alive(pgid) and time.monotonic() < deadline:
            time.sleep(0.05)   # an orphaned member exits after its leader; nothing to wait on
        if not _group_alive(pgid):
            return


def _environ(pid: str) -> bytes:
    try:
        return Path(f"/proc/{pid}/environ").read_bytes()
    except OSError:            # gone, or not ours to read
        return b""


def command_line(pid: int | str) -> str:
    try:
        raw = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return "?"
    return raw.replace(b"\0", b" ").decode(errors="replace").strip() or "?"


def processes_with_env(name: str, value: str, exclude: set[int] | None = None) -> dict[int, str]:
    """``{pid: command line}`` of the live processes whose environment has ``name=value``."""
    marker = f"{name}={value}".encode()
    exclude = exclude or set()
    found: dict[int, str] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) in exclude:
            continue
        if marker in _environ(entry.name).split(b"\0"):
            found[int(entry.name)] = command_line(entry.name)
    return found
