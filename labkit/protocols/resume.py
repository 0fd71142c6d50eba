"""What ``labkit run --resume SESSION`` checks before it trusts a session (docs/reference/protocols.md,
Resume).

* :func:`check_carried_points`: every recorded point belongs to the plan (an integer step in
  range, recorded once, with the step's planned parameters); a point that does not is dropped
  with a ``file:line: reason`` message and its step is measured again. A duplicated step is
  dropped in every copy (which one is right cannot be told) and measured again.
* :func:`rig_differences`: ``--resume S --rig FILE`` may change how devices are reached
  (ports, serial settings), never what is measured: bodies, geometry, limits, control,
  devices (roles, kinds, protocols, options) must be unchanged.
* :class:`ResumeLock`: one process resumes a session at a time (``SESSION/.resume.lock``,
  an advisory lock the kernel releases when the process ends, however it ends). A session
  folder that cannot be written (read-only download) is resumed without the lock: the
  resume writes only its new session, never the old one.
"""

from __future__ import annotations

import errno
import math
import os
from dataclasses import asdict
from pathlib import Path
from typing import Any

from labkit.errors import LabkitError
from labkit.protocols.definition import Step
from labkit.rig import Rig
from labkit.session.paths import session_file

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: no advisory locks, resume is not guarded
    fcntl = None  # type: ignore[assignment]


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, int | float) and isinstance(b, int | float) and not isinstance(a, bool) \
            and not isinstance(b, bool):
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-9)
    return a == b


def _step_of(point: Any) -> int | None:
    if not isinstance(point, dict):
        return None
    step = point.get("step")
    return step if isinstance(step, int) and not isinstance(step, bool) else None


def check_carried_points(sources: list[tuple[str, Any]], steps: list[Step]) -> tuple[list[dict], list[str]]:
    """Points (``(where, point)`` pairs) that match the plan, and a message per dropped one."""
    problems: list[str] = []
    by_step: dict[int, list[tuple[str, dict]]] = {}
    for where, point in sources:
        step = _step_of(point)
        if step is None:
            problems.append(f"{where}: a point without an integer step; ignored")
            continue
        if not 0 <= step < len(steps):  # indices as in results.json (the dry run shows index + 1)
            problems.append(f"{where}: point with step {step} is outside the plan "
                            f"(steps 0 to {len(steps) - 1}); ignored")
            continue
        planned = steps[step].data
        wrong = [k for k, v in planned.items() if k not in point or not _same(point[k], v)]
        if wrong:
            k = wrong[0]
            problems.append(f"{where}: point with step {step} has {k} {point.get(k)!r}, the plan says "
                            f"{planned[k]!r}; dropped, step {step} is measured again")
            continue
        by_step.setdefault(step, []).append((where, point))
    kept: list[dict] = []
    for step in sorted(by_step):
        copies = by_step[step]
        if len(copies) > 1:
            places = ", ".join(w for w, _ in copies)
            problems.append(f"step {step} is recorded {len(copies)} times ({places}); all dropped, "
                            f"step {step} is measured again")
            continue
        kept.append(copies[0][1])
    return kept, problems


def rig_differences(old: Rig, new: Rig) -> list[str]:
    """What differs between a session's rig and a replacement, other than ports and serial settings."""
    diffs: list[str] = []
    for section in ("bodies", "geometry", "limits", "control"):
        a, b = _plain(getattr(old, section)), _plain(getattr(new, section))
        if a != b:
            diffs.append(f"{section} ({_first_difference(a, b)})")
    if set(old.devices) != set(new.devices):
        diffs.append(f"devices (roles {sorted(old.devices)} != {sorted(new.devices)})")
    else:
        for role, dev in old.devices.items():
            other = new.devices[role]
            for attr in ("kind", "protocol", "options"):
                if getattr(dev, attr) != getattr(other, attr):
                    was, now = getattr(dev, attr), getattr(other, attr)
                    diffs.append(f"devices.{role}.{attr} ({was!r} -> {now!r})")
    return diffs


def _plain(value: Any) -> Any:
    if hasattr(value, "__dataclass_fields__"):
        return asdict(value)
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _first_difference(a: Any, b: Any, path: str = "") -> str:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b), key=str):
            if a.get(k) != b.get(k):
                return _first_difference(a.get(k), b.get(k), f"{path}.{k}" if path else str(k))
    return f"{path}: {_shown(a)} -> {_shown(b)}"


def _shown(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else repr(value)


class ResumeLock:
    """``SESSION/.resume.lock`` held (flock) for as long as this process resumes the session."""

    def __init__(self, session: Path) -> None:
        self.path = session_file(session, ".resume.lock")
        self.session = session
        self._file: Any = None

    def acquire(self) -> ResumeLock:
        if fcntl is None:  # pragma: no cover
            return self
        for _ in range(10):  # the file may be removed by its holder between open and flock
            f = self._open()
            if f is None:
                return self  # a read-only session (a download, a shipped recording): nothing to guard
            try:
                fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                f.seek(0)
                holder = f.read(32).strip() or "?"
                f.close()
                raise LabkitError(f"session {self.session} is being resumed by PID {holder}; "
                                  "wait for it to end (or stop it) and resume again") from None
            try:
                same = os.stat(self.path).st_ino == os.fstat(f.fileno()).st_ino
            except FileNotFoundError:
                same = False
            if same:
                f.seek(0)
                f.truncate()
                f.write(f"{os.getpid()}\n")
                f.flush()
                self._file = f
                return self
            f.close()
        raise LabkitError(f"{self.path}: cannot lock the session for resume (lock file keeps changing)")

    def _open(self) -> Any:
        try:
            return open(self.path, "a+", encoding="utf-8")  # noqa: SIM115 - held until release()
        except (PermissionError, OSError) as exc:
            if isinstance(exc, PermissionError) or exc.errno == errno.EROFS:
                return None
            raise LabkitError(f"{self.path}: cannot lock the session for resume: {exc.strerror or exc}") \
                from None

    def release(self) -> None:
        """Remove the lock file (still holding the lock, so no one else holds that inode) and
        drop the lock: a resumed session is left as it was found."""
        if self._file is not None:
            try:
                self.path.unlink()
            except OSError:
                pass
            self._file.close()
            self._file = None
