"""The run's exit paths beyond the protocol's own code: stop signals, a session that cannot
be written, a STOP that could not be delivered (docs/safety.md).
"""

from __future__ import annotations

import signal
from pathlib import Path
from typing import Any

from labkit.errors import LabkitError

#: the signals that take the Ctrl-C path (motors to zero, stop at the next checkpoint)
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT")
                     if hasattr(signal, name))


def signal_name(signum: int) -> str:
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


class SessionGuard:
    """The session as an event sink that stops the run when it cannot write (disk full,
    permissions) instead of being dropped while the motor keeps turning unrecorded."""

    def __init__(self, session: Any, on_failure: Any) -> None:
        self.session = session
        self.on_failure = on_failure
        self.problem: str | None = None

    def on_event(self, event: dict[str, Any]) -> None:
        if self.problem is not None:
            return
        try:
            self.session.on_event(event)
        except (OSError, LabkitError) as exc:
            self.problem = sink_failure_text(self.session, event, exc)
            self.on_failure(self.problem)


def sink_failure_text(session: Any, event: dict[str, Any], exc: BaseException) -> str:
    """``cannot write SESSION/events.jsonl: No space left on device``."""
    if isinstance(exc, LabkitError):
        return str(exc)
    name = (f"readings/{event.get('device')}.jsonl" if event.get("type") == "reading"
            else "events.jsonl")
    return f"cannot write {Path(session.path) / name}: {exc.strerror or exc}"


def stop_failed_text(stop_failed: dict[str, str], offline: bool = False) -> str:
    """``could not stop rotor_motor: port gone (...); cut the motor's power``; ``offline`` (a
    replay, where no motor turns): ``the replayed stop of rotor_motor failed: ...``."""
    if offline:
        return "; ".join(f"the replayed stop of {role} failed: {why}" for role, why in stop_failed.items())
    return "; ".join(f"could not stop {role}: {why}; cut the motor's power"
                     for role, why in stop_failed.items())
