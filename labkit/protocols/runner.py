"""The protocol runner: plan, check, run steps with bluesky-style interruption, always stop safe.

A protocol (:class:`ProtocolDef`) plans a list of :class:`Step` s from the rig and the
parameters, then runs each with plain Python using the :class:`RunContext` verbs ``set``,
``settle``, ``record``, ``sleep`` and ``checkpoint``. The runner

* checks the plan before anything opens: the devices the protocol needs, every target
  against the rig's speed limit, the session directory (``--dry-run`` stops here and
  prints the plan);
* opens the rig (every port recorded into the session's cassettes), starts the speed loops;
* on the first Ctrl-C - or SIGTERM (``kill``), SIGHUP (terminal closed), SIGQUIT (Ctrl-\\),
  SIGTSTP (Ctrl-Z: a run with a turning rotor does not pause) -
  commands every motor to zero at the next control tick and stops at the next checkpoint;
  on a second Ctrl-C trips the interlock at once (docs/explanation/architecture.md#two-ctrl-c); ``run.json``
  names the
  signal (docs/explanation/safety.md);
* whatever happens (interlock, exception, Ctrl-C, normal end) stops the loops, zeroes
  every motor, closes the ports and writes ``results.json`` and the exit status.
"""

from __future__ import annotations

import math
import signal
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from labkit import documents as doc
from labkit.control.loop import SpeedControl, build_speed_control
from labkit.errors import LabkitError, SafetyError
from labkit.io.clock import record_ticks
from labkit.protocols import exit_paths
from labkit.protocols.context import RunContext, StopRequested
from labkit.protocols.declaration import declaration_of
from labkit.protocols.definition import ProtocolDef
from labkit.protocols.events import EventBus, Sink
from labkit.protocols.exit_paths import STOP_SIGNALS, SessionGuard, signal_name, stop_failed_text
from labkit.protocols.operator import Operator, default_operator
from labkit.protocols.plan import check_plan, format_plan
from labkit.rig import Rig, open_rig


def fit_or_error(protocol: Any, points: list[dict[str, Any]]) -> dict[str, Any]:
    """``protocol.fit(points)``, or for a fit that raises, its model with no parameters and the
    error: a failed quick fit must not lose the data (the run, a replay and a re-analysis record
    it the same way)."""
    try:
        return protocol.fit(points)
    except Exception as exc:  # noqa: BLE001 - any failure of a protocol's fit is recorded, not raised
        return {"model": getattr(protocol, "fit_model", "unknown"), "params": {},
                "error": f"{type(exc).__name__}: {exc}"}


def normalise(value: Any) -> Any:
    """JSON-ready copy: NaN/inf -> None, tuples -> lists (what results.json reads back as)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): normalise(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [normalise(v) for v in value]
    return value


@dataclass
class RunOutcome:
    status: str                  # "completed" | "interrupted" | "failed" | "dry-run"
    reason: str | None
    session: Path | None
    results: dict[str, Any] | None
    error: BaseException | None = None
    #: motors whose STOP could not be delivered: {role: reason} (the operator must cut power)
    stop_failed: dict[str, str] = field(default_factory=dict)


class Runner:
    """Runs one protocol on one rig. See the module docstring for the guarantees."""

    def __init__(self, protocol: ProtocolDef, rig: Rig, params: dict[str, Any], *, clock: Any,
                 sinks: list[Sink] | None = None, session: Any = None,
                 previous_points: list[dict[str, Any]] | None = None, done_steps: set[int] | None = None,
                 port_override: Any = None, operator: Operator | None = None, offline: bool = False,
                 run_id: str | None = None) -> None:
        self.protocol = protocol
        self.rig = rig
        self.params = params
        self.clock = clock
        #: every document carries the run's id (``run_id``: a resumed run's is the first run's)
        self.bus = EventBus(sinks, run_id)
        self.run_id = self.bus.run_id
        self.session = session
        if session is not None:
            self.bus.add(session)
        self.previous_points = list(previous_points or [])
        self.done_steps = set(done_steps or ())
        self.port_override = port_override
        self.offline = offline  # a replay: no motor turns, nothing tells a person to cut power
        self.ports: dict[str, Any] = {}  # the ports the run opened, by role (a replay reads them)
        self.operator = operator if operator is not None else default_operator(clock)
        self.stop_count = 0
        self.stop_signal: str | None = None   # "SIGTERM", ... (None: Ctrl-C or not stopped)
        #: a recorder or the session writer failed (disk full...): the run stops safely
        self.health_problem: str | None = None
        self._recording_ports: list[Any] = []
        self._saving = False
        self.control: SpeedControl | None = None
        self.steps = protocol.plan(rig, params)
        check_plan(protocol, rig, self.steps)

    def dry_run(self) -> str:
        return format_plan(self.protocol, self.rig, self.steps, self.done_steps)

    # ---- Ctrl-C and stop signals --------------------------------------------------------
    @property
    def stop_cause(self) -> str:
        return exit_paths.stop_cause_of(self.stop_signal)

    def request_stop(self, signum: int = signal.SIGINT) -> None:
        """What Ctrl-C does: 1st - motors to zero at the next tick, stop at next checkpoint;
        2nd - interlock now (every motor zero) and KeyboardInterrupt.

        SIGTERM, SIGHUP and SIGQUIT do what the first Ctrl-C does; repeating them (a shell
        and a supervisor may both pass on one SIGHUP) never escalates: only Ctrl-C does.
        """
        name = signal_name(signum)
        first = self.stop_count == 0
        if first:
            self.stop_signal = name
        if not first and signum != signal.SIGINT:
            return
        self.stop_count += 1
        self.bus.emit(doc.StopRequest(t=self.clock.now(), count=self.stop_count, signal=name))
        if self._saving:
            return  # motors are already at zero; let results.json and run.json be written whole
        if self.stop_count == 1:
            if self.control is not None:
                self.control.request_zero()
        else:
            if self.control is not None:
                self.control.trip("Ctrl-C pressed twice")
            raise KeyboardInterrupt

    def _install_signal_handlers(self) -> dict[int, Any]:
        """Ctrl-C, SIGTERM, SIGHUP and SIGQUIT -> :meth:`request_stop`; the previous handlers."""
        if threading.current_thread() is not threading.main_thread():
            return {}
        previous = {}
        for signum in STOP_SIGNALS:
            previous[signum] = signal.signal(signum, lambda number, frame: self.request_stop(number))
        return previous

    # ---- recorder and session health -----------------------------------------------------
    def _guard_session(self) -> None:
        for i, sink in enumerate(self.bus.sinks):
            if sink is self.session:
                self.bus.sinks[i] = SessionGuard(self.session, self._sink_failed)

    def _sink_failed(self, problem: str) -> None:
        """A sink could not write: motors to zero now (interlock), the run stops."""
        if self.health_problem is None:
            self.health_problem = problem
        if self.control is not None and self.control.tripped is None and not self._saving:
            self.control.trip(problem)

    def health(self) -> str | None:
        """The first recorder/session failure, or None. Never raises (called in the control tick)."""
        if self.health_problem is None:
            for port in self._recording_ports:
                problem = getattr(port, "record_error", None)
                if problem:
                    self.health_problem = problem
                    break
        return self.health_problem

    def check_health(self) -> None:
        """Raise SafetyError (motors zeroed first) when a recorder or the session failed."""
        problem = self.health()
        if problem is None:
            return
        if self.control is not None:
            if self.control.tripped is None:
                self.control.trip(problem)
            self.control.check()
        raise SafetyError(f"{problem}; motors commanded to zero")

    # ---- the run ------------------------------------------------------------------------
    def run(self) -> RunOutcome:
        status, reason = "completed", None
        error: BaseException | None = None
        new_points: list[dict[str, Any]] = []
        opened = None
        pulse = None
        ctx: RunContext | None = None
        previous_handlers = self._install_signal_handlers()
        self._guard_session()
        cassettes = self.session.cassette_dir if self.session is not None else None
        ticks = record_ticks(self.clock, self.session.path) if self.session is not None else None
        self.bus.emit(doc.RunStart(
            t=self.clock.now(), protocol=self.protocol.name, params=self.params, rig=self.rig.name,
            n_steps=len(self.steps), session=str(self.session.path) if self.session is not None else None,
            resumed_from=(self.session.meta.get("resumed_from") if self.session else None),
            **declaration_of(self.protocol)))
        try:
            opened = open_rig(self.rig, self.clock, record_to=cassettes, port_override=self.port_override)
            self.ports = {role: getattr(dev, "port", None) for role, dev in opened.drivers.items()}
            self._recording_ports = [dev.port for dev in opened.drivers.values()
                                     if hasattr(getattr(dev, "port", None), "record_error")]
            self.control = build_speed_control(opened, self.clock, emit=self.bus.emit)
            self.control.guards.append(self.health)
            pulse = exit_paths.watch_run(self.control, self.session)  # session folder, supervisor's heartbeat
            ctx = RunContext(self, opened.drivers, self.control)
            self.protocol.setup(ctx)
            for step in self.steps:
                if step.index in self.done_steps:
                    continue
                ctx.checkpoint()
                ctx.step = step
                self.bus.emit(doc.StepStart(t=self.clock.now(), index=step.index, n_steps=len(self.steps),
                                            label=step.label, targets_rad_s=step.targets_rad_s,
                                            eta_s=step.est_duration_s))
                point = self.protocol.run_step(ctx, step)
                self.control.check()  # an interlock that tripped in the step's last moments: no point
                point = normalise({"step": step.index, **point})
                new_points.append(point)
                self.bus.emit(doc.PointDone(t=self.clock.now(), index=step.index, point=point))
                self.bus.emit(doc.Checkpoint(t=self.clock.now(), index=step.index))
        except StopRequested as exc:
            status, reason, error = "interrupted", str(exc), exc
        except KeyboardInterrupt as exc:
            status, reason, error = "interrupted", "Ctrl-C pressed twice; motors commanded to zero", exc
        except BaseException as exc:  # noqa: BLE001 - every exit path ends in the safe state
            status = "failed"
            reason = str(exc) if isinstance(exc, LabkitError) else f"{type(exc).__name__}: {exc}"
            error = exc
            if not (self.control is not None and self.control.tripped):
                self.bus.emit(doc.Fault(t=self.clock.now(), reason=reason))
        finally:
            self._saving = True  # from here on Ctrl-C only counts (QCoDeS' DelayedKeyboardInterrupt)
            if self.control is not None:
                self.control.stop()
            if opened is not None:
                opened.close()
            if pulse is not None:
                pulse.stop()  # motors stopped, ports closed: a supervisor need not watch any more
            if ticks is not None:
                ticks.close()
        stop_failed = dict(opened.stop_failures) if opened is not None else {}
        if stop_failed:
            self.bus.emit(doc.StopFailed(t=self.clock.now(), devices=dict(stop_failed)))
            if reason:  # "motors commanded to zero" is not the whole truth any more
                reason = reason.replace("; motors commanded to zero", "").replace("; motors at zero", "")
            reason = stop_failed_text(stop_failed, self.offline) + (f" (after: {reason})" if reason else "")
            status = "failed" if status == "completed" else status
        try:
            outcome = self._save(status, reason, error, ctx, new_points, stop_failed)
            outcome.stop_failed = stop_failed
            return outcome
        finally:
            for signum, handler in previous_handlers.items():
                signal.signal(signum, handler)

    def _save(self, status: str, reason: str | None, error: BaseException | None, ctx: RunContext | None,
              new_points: list[dict[str, Any]], stop_failed: dict[str, str] | None = None) -> RunOutcome:
        if ctx is not None:
            ctx.log_tach_readings()
        points = self.previous_points + new_points
        fit = fit_or_error(self.protocol, points)
        results = normalise({"protocol": self.protocol.name, "points": points, "fit": fit})
        self.bus.emit(doc.Results(t=self.clock.now(), results=results))
        steps_done = len(self.done_steps) + len(new_points)
        self.bus.emit(doc.RunStop(t=self.clock.now(), status=status, reason=reason, steps_done=steps_done))
        if self.session is not None:
            if self.stop_signal is not None:
                self.session.meta["signal"] = self.stop_signal
            if stop_failed:
                self.session.meta["stop_failed"] = stop_failed
            try:
                self.session.write_results(results)
                self.session.finish(status, reason)
            except (OSError, LabkitError) as exc:
                # the motors are already stopped; what is on disk stays readable and resumable
                problem = str(exc) if isinstance(exc, LabkitError) else (
                    f"cannot write {exc.filename or self.session.path}: {exc.strerror or exc}")
                if self.health_problem is None:  # a sink failure already named the file
                    reason = f"{reason}; {problem}" if reason else problem
                status = "failed" if status == "completed" else status
        return RunOutcome(status, reason, self.session.path if self.session else None, results, error)

