"""Everything ``labkit run``, ``labkit demo`` and ``labkit replay`` share, as plain functions.

* :func:`prepare_run` resolves rig, protocol and parameters (or a session to resume),
  checks the plan against the rig's limits and that sessions can be written: every bad
  input fails here, before any port is opened or any motor turns.
* :func:`execute` runs a prepared plan into a new session directory.
* what a resumed run and a replay read of a session (its points, its cassettes' URLs) is in
  :mod:`labkit.protocols.recorded`; :mod:`labkit.protocols.replay` builds on both.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from labkit.errors import LabkitError
from labkit.io.clock import Clock, RealClock, VirtualClock, use_clock
from labkit.protocols.analysis_versions import RUN_KEY, versions_of
from labkit.protocols.definition import ProtocolDef
from labkit.protocols.events import Sink
from labkit.protocols.params import resolve_params
from labkit.protocols.recorded import recorded_points
from labkit.protocols.registry import get_protocol
from labkit.protocols.resume import ResumeLock, check_carried_points, rig_differences
from labkit.protocols.resume_evidence import check_points_against_cassettes
from labkit.protocols.runner import Runner, RunOutcome
from labkit.rig import Rig, load_rig
from labkit.session import Session, SessionRecord, check_writable, load_session_record


@dataclass
class PreparedRun:
    rig: Rig
    protocol: ProtocolDef
    params: dict[str, Any]
    clock: Clock
    runner: Runner
    resumed_from: SessionRecord | None = None
    carried_points: list[dict[str, Any]] = field(default_factory=list)
    #: one line each: damaged lines skipped, recorded points dropped (printed by the CLI)
    warnings: list[str] = field(default_factory=list)
    lock: ResumeLock | None = None


def all_simulated(rig: Rig) -> bool:
    return all(d.port.startswith("sim://") for d in rig.devices.values())


def make_clock(kind: str, rig: Rig) -> Clock:
    """``auto``: virtual when every device is emulated (sim://), else real."""
    if kind == "virtual" or (kind == "auto" and all_simulated(rig)):
        return VirtualClock()
    if kind in ("real", "auto"):
        return RealClock()
    raise LabkitError(f"--clock {kind!r}: expected auto, real or virtual")


def fresh_emulators(rig: Rig) -> None:
    """A new run on emulators starts from rest: the current emulation's plants are forgotten
    (:class:`labkit.emulators.Emulation`; a test's own, or the process's)."""
    if any(d.port.startswith("sim://") for d in rig.devices.values()):
        from labkit.emulators import current_emulation

        current_emulation().bind_rig(rig)  # model plants (plant=model-*) read its magnets


def carried_points(record: SessionRecord) -> list[dict[str, Any]]:
    """All result rows a session holds: those it carried from earlier runs plus its own
    (as recorded, unchecked; :func:`recorded_points` says where each comes from)."""
    return list(record.meta.get("carried_points") or []) + record.completed_points()


def resume_rig(record: SessionRecord, rig_path: str | Path | None, resume: str | Path) -> Rig:
    """The session's rig, or ``rig_path`` when it differs only in ports and serial settings."""
    session_rig = load_rig(record.rig_path())
    if rig_path is None:
        return session_rig
    rig = load_rig(rig_path)
    diffs = rig_differences(session_rig, rig)
    if diffs:
        raise LabkitError(f"--resume {resume} --rig {rig_path}: only ports and serial settings may change, "
                          f"but {'; '.join(diffs)} differ from the session's rig.toml")
    return rig


def prepare_run(rig_path: str | Path | None, protocol_name: str | None, sets: list[str] | None, *,
                clock: str = "auto", session_root: str | Path | None = "sessions",
                resume: str | Path | None = None, sinks: list[Sink] | None = None) -> PreparedRun:
    """Validate everything and build the runner; nothing is opened yet.

    With ``resume`` (and ``session_root``: not a dry run) the session is locked against a
    second resume until :func:`execute` ends (or :meth:`PreparedRun.lock` is released)."""
    if resume is None:
        return _prepare(rig_path, protocol_name, sets, clock, session_root, None, sinks)
    lock = ResumeLock(Path(resume)).acquire() if session_root is not None and Path(resume).is_dir() else None
    try:
        prep = _prepare(rig_path, protocol_name, sets, clock, session_root, resume, sinks)
    except BaseException:
        if lock is not None:
            lock.release()
        raise
    prep.lock = lock
    return prep


def _prepare(rig_path: str | Path | None, protocol_name: str | None, sets: list[str] | None, clock: str,
             session_root: str | Path | None, resume: str | Path | None,
             sinks: list[Sink] | None) -> PreparedRun:
    record = None
    warnings: list[str] = []
    if resume is not None:
        record = load_session_record(resume)
        warnings += record.problems
        rig = resume_rig(record, rig_path, resume)
        if protocol_name and protocol_name != record.protocol:
            raise LabkitError(f"--resume {resume}: that session ran {record.protocol}, not {protocol_name}")
        protocol = get_protocol(record.protocol)
        params = resolve_params(protocol.defaults, record.params, protocol.name, protocol.bounds)
        if sets:
            raise LabkitError("--resume continues with the session's own parameters; drop --set")
    else:
        if rig_path is None or protocol_name is None:
            raise LabkitError("give RIG and PROTOCOL (or --resume SESSION)")
        rig = load_rig(rig_path)
        protocol = get_protocol(protocol_name)
        params = resolve_params(protocol.defaults, sets, protocol.name, protocol.bounds)
    if record is not None and clock == "auto" and record.meta.get("clock") == "real":
        clock = "real"  # a real-clock session resumes on the real clock, even on emulators
    the_clock = make_clock(clock, rig)
    points: list[dict[str, Any]] = []
    if record is not None:
        points, dropped = check_carried_points(recorded_points(record), protocol.plan(rig, params))
        points, notes = check_points_against_cassettes(record, resume, points)
        warnings += dropped + notes
    done = {int(p["step"]) for p in points}
    runner = Runner(protocol, rig, params, clock=the_clock, sinks=sinks, previous_points=points,
                    done_steps=done, run_id=record.run_id if record is not None else None)
    if record is not None and len(done) >= len(runner.steps):
        lost = "" if record.results is not None else (
            f"; only its results.json is missing (deleted, or the run was killed after its last point): "
            f"`labkit report {resume}` and `labkit fit {resume}` take the results from events.jsonl")
        raise LabkitError(f"--resume {resume}: all {len(runner.steps)} steps are already done{lost}")
    if session_root is not None:
        check_writable(session_root)
    return PreparedRun(rig, protocol, params, the_clock, runner, record, points, warnings)


def execute(prep: PreparedRun, session_root: str | Path | None = "sessions", notes: str = "",
            on_session: Callable[[Runner, Session], None] | None = None) -> RunOutcome:
    """Run a prepared plan, writing a session under ``session_root`` (None: no session).

    ``on_session(runner, session)`` is called once the session exists, before any port
    opens (the CLI adds its rerun sink there).
    """
    try:
        return _execute(prep, session_root, notes, on_session)
    finally:
        if prep.lock is not None:
            prep.lock.release()


class _StepSeen:
    """Sink noting whether the run reached its first step (before it, nothing was measured)."""

    def __init__(self) -> None:
        self.seen = False

    def on_event(self, event: Any) -> None:
        # a plain dict or a typed run document (``.type``); never raises, never converts
        kind = event.get("type") if isinstance(event, dict) else getattr(event, "type", None)
        if kind == "step":
            self.seen = True


def _execute(prep: PreparedRun, session_root: str | Path | None, notes: str,
             on_session: Callable[[Runner, Session], None] | None) -> RunOutcome:
    runner = prep.runner
    step_seen = _StepSeen()
    runner.bus.add(step_seen)
    session = None
    if session_root is not None:
        session = Session.create(
            session_root, protocol=prep.protocol.name, params=_jsonable(prep.params), rig_name=prep.rig.name,
            rig_text=prep.rig.text, clock="virtual" if prep.clock.is_virtual else "real", notes=notes,
            resumed_from=str(prep.resumed_from.path) if prep.resumed_from else None, run_id=runner.run_id)
        session.update_meta(carried_points=prep.carried_points,
                            steps_planned=len(runner.steps), resume_warnings=prep.warnings)
        if versions_of(prep.protocol):  # the image analysis that makes its points, by version
            session.update_meta(**{RUN_KEY: versions_of(prep.protocol)})
        runner.session = session
        runner.bus.add(session)
        if on_session is not None:
            on_session(runner, session)
    if prep.clock.is_virtual:
        fresh_emulators(prep.rig)
    with use_clock(prep.clock):
        outcome = runner.run()
    if outcome.status == "failed" and not step_seen.seen and session is not None:
        # nothing was measured (a port did not open, the balance did not answer...): the
        # session holds nothing to resume, so it is removed and the message says what to fix
        shutil.rmtree(session.path, ignore_errors=True)
        outcome.session = None
        outcome.reason = f"{outcome.reason} (before the first step: nothing measured, no session kept)"
        if prep.resumed_from is not None:
            old = prep.resumed_from.path
            outcome.reason += f"; fix the cause, then: labkit run --resume {old} [--rig FIXED.toml]"
    return outcome


def _jsonable(params: dict[str, Any]) -> dict[str, Any]:
    return json.loads(json.dumps(params))
