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
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from labkit import documents as doc
from labkit.control.loop import SpeedControl, build_speed_control
from labkit.devices.base import Device
from labkit.devices.kinds import (
    BalanceKind,
    CameraKind,
    MotorKind,
    MotorStatusKind,
    StrobeKind,
    TachometerKind,
)
from labkit.errors import LabkitError, SafetyError
from labkit.io.clock import record_ticks
from labkit.protocols import exit_paths
from labkit.protocols.declaration import declaration_of
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.events import EventBus, Sink, not_logged
from labkit.protocols.exit_paths import STOP_SIGNALS, SessionGuard, signal_name, stop_failed_text
from labkit.protocols.operator import Operator, default_operator
from labkit.protocols.plan import check_plan, format_plan
from labkit.readings import Reading
from labkit.rig import Rig, open_rig
from labkit.units import rad_s_to_rpm

CONTROL_EVENT_INTERVAL_S = 0.25


def normalise(value: Any) -> Any:
    """JSON-ready copy: NaN/inf -> None, tuples -> lists (what results.json reads back as)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): normalise(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [normalise(v) for v in value]
    return value


class StopRequested(LabkitError):
    """The operator asked to stop (Ctrl-C or a stop signal); the run ended at a checkpoint,
    motors at zero."""


class RunContext:
    """What a step function may do. Every wait polls the interlocks and is a checkpoint."""

    def __init__(self, runner: Runner, devices: Mapping[str, Device], control: SpeedControl) -> None:
        self.runner = runner
        self.clock = runner.clock
        self.rig = runner.rig
        self.params = runner.params
        #: the open drivers by role (motors too: steps command them through ``set``)
        self.devices = devices
        self.control = control
        self.step: Step | None = None
        self._last_control_event = -1e9
        self._streams: dict[str, doc.StreamDescriptor] = {}   # role -> its stream's descriptor
        #: per streaming device, the time of the last reading logged and how many had that time
        self._tach_logged: dict[str, tuple[float, int]] = {
            role: (-1e9, 0) for role in devices if self.rig.devices[role].kind == "tachometer"}
        self._strobe_logged: dict[str, tuple[float, int]] = {
            role: (-1e9, 0) for role in devices if self.rig.devices[role].kind == "strobe"}

    # ---- devices by kind (labkit.devices.kinds; LabkitError naming the rig's devices if not) -
    def balance(self, role: str) -> BalanceKind:
        if isinstance(device := self.devices.get(role), BalanceKind):
            return device
        raise self._not_a(role, "balance")

    def tachometer(self, role: str) -> TachometerKind:
        if isinstance(device := self.devices.get(role), TachometerKind):
            return device
        raise self._not_a(role, "tachometer")

    def motor(self, role: str) -> MotorStatusKind:
        """The motor controller ``role``, for its ``status()``: speeds go through :meth:`set` (the
        rig's speed loop), so the type offers no ``set_duty``."""
        if isinstance(device := self.devices.get(role), MotorKind):
            return device
        raise self._not_a(role, "motor controller")

    def camera(self, role: str) -> CameraKind:
        if isinstance(device := self.devices.get(role), CameraKind):
            return device
        raise self._not_a(role, "camera")

    def strobe(self, role: str) -> StrobeKind:
        if isinstance(device := self.devices.get(role), StrobeKind):
            return device
        raise self._not_a(role, "strobe")

    def _not_a(self, role: str, what: str) -> LabkitError:
        have = ", ".join(f"{r} ({self.rig.devices[r].kind})" for r in sorted(self.devices)) or "none"
        return LabkitError(f"{self.rig.path}: this protocol needs a {what} called {role!r}; "
                           f"the rig has {have}")

    # ---- events -------------------------------------------------------------------------
    def now(self) -> float:
        return self.clock.now()

    def emit(self, event: doc.RunDocument | dict[str, Any]) -> None:
        """Hand a document to the sinks (a plain dict without ``t`` is stamped now)."""
        self.runner.bus.emit(doc.as_document(event, self.clock.now()))

    def emit_reading(self, role: str, reading: Reading) -> None:
        """The reading itself, flags and raw bytes included, as a ``reading`` document; the
        first of a device (or one whose quantity or unit differs from the stream's so far)
        after a ``descriptor`` declaring them."""
        described = self._streams.get(role)
        if described is None or not described.declares(reading):
            spec = self.rig.devices.get(role)
            kind, driver = (spec.kind, spec.protocol) if spec is not None else ("", "")
            described = self._streams[role] = doc.StreamDescriptor.of(role, reading, kind, driver)
            self.emit(described)
        self.emit(doc.ReadingEvent.of(role, reading))

    def log_tach_readings(self) -> None:
        """Emit the tachometers' new readings, and the strobes' new status lines (f_rot,
        f_strobe, flags: :meth:`labkit.devices.strobe.protocol.StrobeStatus.reading`), as
        ``reading`` events (readings/ROLE.jsonl)."""
        for role, mark in self._tach_logged.items():
            try:
                new, self._tach_logged[role] = not_logged(self.tachometer(role).readings_since, mark)
            except Exception:  # noqa: BLE001 - a dead tachometer is the interlock's business
                continue
            for reading in new:
                self.emit_reading(role, reading)
        for role, mark in self._strobe_logged.items():
            try:
                lines, self._strobe_logged[role] = not_logged(self.strobe(role).statuses_since, mark)
            except Exception:  # noqa: BLE001 - a strobe that stopped talking fails the burst, not this
                continue
            for status in lines:
                self.emit_reading(role, status.reading())

    def _control_event(self) -> None:
        now = self.clock.now()
        if now - self._last_control_event < CONTROL_EVENT_INTERVAL_S:
            return
        self._last_control_event = now
        self.log_tach_readings()
        loops = {name: {"target_rad_s": s.target_rad_s, "setpoint_rad_s": s.setpoint_rad_s,
                        "measured_rad_s": s.measured_rad_s, "duty": s.duty, "settled": s.settled}
                 for name, s in self.control.snapshots().items()}
        self.emit(doc.ControlSnapshot(t=now, loops=loops))

    # ---- verbs --------------------------------------------------------------------------
    def operator_signalled(self) -> bool:
        """True once per operator signal (the Enter key on a terminal) since the last call;
        never blocks. Virtual-clock runs have no operator unless one is given to the runner."""
        return self.runner.operator.signalled()

    def discard_operator_signals(self) -> None:
        """Forget signals given before now (a key pressed while nothing was watched)."""
        self.runner.operator.discard()

    def checkpoint(self) -> None:
        """Raise if an interlock tripped, a recorder failed or the operator asked to stop."""
        self.runner.check_health()
        self.control.check()
        if self.runner.stop_count:
            raise StopRequested(f"stopped by {self.runner.stop_cause} at a checkpoint; motors at zero")

    def set(self, **targets_rad_s: float) -> None:
        """Set speed-loop targets in rad/s (ramped at the rig's limit), e.g. ``set(rotor=1000)``."""
        self.checkpoint()
        self.control.set_targets(targets_rad_s)
        for loop, target in targets_rad_s.items():
            self.emit(doc.Setpoint(t=self.clock.now(), loop=loop, target_rad_s=target))

    def sleep(self, duration_s: float) -> None:
        """Wait ``duration_s`` on the clock in control periods, checking at each."""
        end = self.clock.now() + duration_s
        period = self.control.period_s
        while True:
            self.checkpoint()
            remaining = end - self.clock.now()
            if remaining <= 1e-12:
                return
            self.clock.sleep(min(period, remaining))
            self._control_event()

    def settle(self, timeout_s: float | None = None) -> float:
        """Wait until every loop holds its target within tolerance for the hold time.

        Returns the settle time (s). Raises :class:`LabkitError` (run ends, motors zero) if
        it does not settle within ``timeout_s`` (default: the rig's ``settle_timeout``).
        """
        timeout = timeout_s if timeout_s is not None else self.rig.control.settle_timeout_s
        start = self.clock.now()
        while True:
            self.checkpoint()
            if self.control.settled():
                took = self.clock.now() - start
                speeds = {n: s.measured_rad_s for n, s in self.control.snapshots().items()}
                self.emit(doc.Settled(t=self.clock.now(), index=self.step.index if self.step else None,
                                      settle_time_s=took, speeds_rad_s=speeds))
                return took
            if self.clock.now() - start > timeout:
                snaps = self.control.snapshots()
                state = ", ".join(
                    f"{n}: target {rad_s_to_rpm(s.target_rad_s):.0f} RPM, measured "
                    + ("none" if s.measured_rad_s is None else f"{rad_s_to_rpm(s.measured_rad_s):.0f} RPM")
                    for n, s in snaps.items())
                raise LabkitError(f"speed did not settle within {timeout:.0f} s ({state}); motors at zero")
            self.clock.sleep(self.control.period_s)
            self._control_event()

    def wait_stopped(self, loop: str = "rotor", below_rad_s: float = 5.0, timeout_s: float = 30.0) -> None:
        """Command ``loop`` to zero and wait until its tachometer reads below ``below_rad_s``."""
        self.set(**{loop: 0.0})
        tach = self.tachometer(self.rig_loop(loop).tach)
        start = self.clock.now()
        while True:
            self.checkpoint()
            reading = tach.latest()
            if reading is not None and reading.t > start and reading.value < below_rad_s:
                return
            if self.clock.now() - start > timeout_s:
                raise LabkitError(f"{loop} did not stop within {timeout_s:.0f} s")
            self.clock.sleep(self.control.period_s)
            self._control_event()

    def rig_loop(self, name: str) -> Any:
        for lc in self.rig.control.loops:
            if lc.name == name:
                return lc
        raise LabkitError(f"no speed loop {name!r} in {self.rig.path}")

    def read(self, role: str) -> Reading:
        """One balance reading (emitted as a ``reading`` event)."""
        reading = self.balance(role).read()
        self.emit_reading(role, reading)
        return reading

    def record(self, role: str, duration_s: float, min_n: int = 1) -> list[Reading]:
        """Balance readings for ``duration_s`` (at least ``min_n``), each a checkpoint."""
        device = self.balance(role)
        start = self.clock.now()
        out: list[Reading] = []
        while self.clock.now() - start < duration_s or len(out) < min_n:
            self.checkpoint()
            reading = device.read()
            self.emit_reading(role, reading)
            out.append(reading)
            self._control_event()
        # a plausibility violation pending at the end trips (no point) or clears first
        self.control.await_verdict(self.clock.now(), self.checkpoint, self._control_event)
        return out

    def tach_readings(self, role: str, since: float) -> list[Reading]:
        return list(self.tachometer(role).readings_since(since))


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
        results = normalise({"protocol": self.protocol.name, "points": points, "fit": self._fit(points)})
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

    def _fit(self, points: list[dict[str, Any]]) -> dict[str, Any]:
        try:
            return self.protocol.fit(points)
        except Exception as exc:  # noqa: BLE001 - a failed quick fit must not lose the data
            return {"model": getattr(self.protocol, "fit_model", "unknown"), "params": {},
                    "error": f"{type(exc).__name__}: {exc}"}
