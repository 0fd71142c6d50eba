"""The run's exit paths beyond the protocol's own code: stop signals, a session that cannot
be written, a STOP that could not be delivered (docs/explanation/safety.md).
"""

from __future__ import annotations

import signal
from pathlib import Path
from typing import Any

from labkit.documents import RunDocument
from labkit.errors import LabkitError

#: the signals that take the Ctrl-C path (motors to zero, stop at the next checkpoint); Ctrl-Z
#: (SIGTSTP) too: a run cannot pause with a rotor turning under nobody's control
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT", "SIGTSTP")
                     if hasattr(signal, name))
#: what the run says stopped it, for signals whose name a user may not know
SIGNAL_CAUSES = {"SIGTSTP": "SIGTSTP (Ctrl-Z: a run does not pause, it stops)"}


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

    def on_event(self, event: RunDocument) -> None:
        if self.problem is not None:
            return
        try:
            self.session.on_event(event)
        except (OSError, LabkitError) as exc:
            self.problem = sink_failure_text(self.session, event, exc)
            self.on_failure(self.problem)


def stop_cause_of(stop_signal: str | None) -> str:
    """``Ctrl-C`` for SIGINT (or no signal), else the signal's name, explained where needed."""
    if stop_signal in (None, "SIGINT"):
        return "Ctrl-C"
    return SIGNAL_CAUSES.get(stop_signal, stop_signal)


def watch_run(control: Any, session: Any) -> Any:
    """Guards a run adds to its speed control: the session folder must stay (every tick), and
    in a supervised worker the supervisor's heartbeat beats from the tick; the pulse to stop
    once the motors are stopped and the ports closed (None in a one-process run)."""
    if session is not None:
        control.guards.append(SessionFolderWatch(session.path))
    from labkit.control.supervisor import worker_heartbeat

    heartbeat = worker_heartbeat()
    if heartbeat is None:
        return None
    from labkit.control.heartbeat import WorkerPulse

    return WorkerPulse(heartbeat, control).start()


class SessionFolderWatch:
    """A guard of the speed control: the session folder deleted or moved away mid-run stops the
    run at the next tick. Open files keep accepting writes into a deleted folder without an
    error, so without this the rotor turned on, unrecorded (issue 29: 18 s at 13 175 RPM)."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self.identity = _identity(self.folder)

    def __call__(self) -> str | None:
        if self.identity is None:
            return None
        now = _identity(self.folder)
        if now == self.identity:
            return None
        what = "deleted" if now is None else "replaced by another folder"
        return (f"session folder {self.folder} was {what} during the run; nothing more can be recorded, "
                "so the run stops")


def _identity(folder: Path) -> tuple[int, int] | None:
    try:
        st = folder.stat()
    except OSError:
        return None
    return (st.st_dev, st.st_ino)


def sink_failure_text(session: Any, event: RunDocument, exc: OSError | LabkitError) -> str:
    """``cannot write SESSION/events.jsonl: No space left on device``."""
    if isinstance(exc, LabkitError):
        return str(exc)
    name = (f"readings/{event.get('device')}.jsonl" if event.get("type") in ("reading", "descriptor")
            else "events.jsonl")
    return f"cannot write {Path(session.path) / name}: {exc.strerror or exc}"


def stop_failed_text(stop_failed: dict[str, str], offline: bool = False) -> str:
    """``could not stop rotor_motor: port gone (...); cut the motor's power``; ``offline`` (a
    replay, where no motor turns): ``the replayed stop of rotor_motor failed: ...``."""
    if offline:
        return "; ".join(f"the replayed stop of {role} failed: {why}" for role, why in stop_failed.items())
    return "; ".join(f"could not stop {role}: {why}; cut the motor's power"
                     for role, why in stop_failed.items())
