"""Closed-loop rotor speed: a motor controller steered by a tachometer, with interlocks.

:class:`SpeedControl` runs one or two :class:`SpeedLoop` s as one clock job (a thread on a
real clock, in-line on a virtual one). Every control period each loop

1. checks its interlocks: tachometer silent (no reading for ``tach_timeout_s``) or
   disconnected, implausible reading (not finite, negative, above twice the limit),
   over-speed (above ``max_speed*(1+overspeed_margin)``), controller error flags;
   (read every ``status_period_s``; the trip follows in the tick that reads them);
2. checks that the reading is plausible for the duty it commanded
   (:mod:`labkit.control.plausibility`: reads far too low or too high for the feed-forward,
   stuck, stalled motor; and against the controller's own speed where it reports one);
3. moves its ramped setpoint toward the target at the rig's ``max_ramp``;
4. commands feed-forward + PI duty (:func:`labkit.control.pi.pi_step`), capped so that the
   feed-forward speed ``duty * full_speed`` stays at or below the rig's ``max_speed``
   whatever the tachometer says (:func:`duty_cap`);
5. updates its settle detector.

Any trip, and any exception inside a tick, commands *every* motor of the rig to zero in
that same tick and latches the reason; :meth:`SpeedControl.check` raises it as
:class:`labkit.errors.SafetyError` in the protocol's thread.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from labkit.control import plausibility as plaus
from labkit.control.pi import PIGains, PIState, SettleDetector, pi_step, ramp_toward
from labkit.control.stopping import stop_motor
from labkit.devices.kinds import MotorKind, TachometerKind
from labkit.documents import Interlock, RunDocument
from labkit.errors import LabkitError, SafetyError
from labkit.units import rad_s_to_rpm

Emit = Callable[[RunDocument], None]


@dataclass
class LoopSnapshot:
    """What a loop knows after its last tick (for events, progress and rerun)."""

    t: float
    target_rad_s: float
    setpoint_rad_s: float
    measured_rad_s: float | None
    duty: float
    settled: bool


class Tripped(Exception):
    """Raised inside a tick to trip the interlock with a reason."""


class SpeedLoop:
    """One motor + one tachometer. Not thread-safe on its own: :class:`SpeedControl` locks."""

    def __init__(self, name: str, motor: MotorKind, tach: TachometerKind, *, period_s: float, gains: PIGains,
                 max_speed_rad_s: float, max_ramp_rad_s2: float, overspeed_margin: float,
                 settle_tolerance_rad_s: float, settle_hold_s: float, tach_timeout_s: float,
                 status_period_s: float = 0.0,
                 plausibility: plaus.PlausibilitySettings | None = None) -> None:
        self.name, self.motor, self.tach = name, motor, tach
        #: None: the tachometer is trusted as it reads (only SpeedLoops built by hand)
        self.plausibility = plausibility
        self.plausible = plaus.PlausibilityState()
        self.last_reading_t: float | None = None
        self.period_s = period_s
        self.gains = gains
        self.max_speed = max_speed_rad_s
        self.max_ramp = max_ramp_rad_s2
        self.overspeed = max_speed_rad_s * (1.0 + overspeed_margin)
        self.tach_timeout = tach_timeout_s
        self.status_period = status_period_s
        self.last_status_t: float | None = None
        self.state = PIState()
        self.settle = SettleDetector(settle_tolerance_rad_s, settle_hold_s)
        self.target = 0.0
        self.setpoint = 0.0
        self.enabled = False
        self.started_at: float | None = None
        self.last_t: float | None = None
        self.snapshot = LoopSnapshot(0.0, 0.0, 0.0, None, 0.0, False)

    def set_target(self, speed_rad_s: float) -> None:
        if not math.isfinite(speed_rad_s) or speed_rad_s < 0:
            raise SafetyError(f"{self.name}: target speed {speed_rad_s!r} rad/s is not allowed")
        if speed_rad_s > self.max_speed:
            raise SafetyError(
                f"{self.name}: target {speed_rad_s * 60 / (2 * math.pi):.0f} RPM is above the rig's "
                f"limit of {self.max_speed * 60 / (2 * math.pi):.0f} RPM")
        if self.plausibility is not None:
            problem = plaus.unreachable(self.plausibility, speed_rad_s, self.gains.max_duty)
            if problem:
                raise SafetyError(f"{self.name}: {problem}")
        self.target = speed_rad_s
        self.settle.reset()
        self.snapshot = replace(self.snapshot, target_rad_s=speed_rad_s, settled=False)

    def _measure(self, t: float) -> float | None:
        try:
            reading = self.tach.latest()  # raises when the port is gone (real I/O, not is_open)
        except Exception as exc:  # noqa: BLE001 - any tach fault is an interlock
            raise Tripped(f"tachometer {self.tach.name} lost: {exc}") from exc
        since = reading.t if reading is not None else self.started_at
        moving = self.target > 0 or self.setpoint > 0
        if moving and since is not None and t - since > self.tach_timeout:
            raise Tripped(f"tachometer {self.tach.name} silent for {t - since:.2f} s "
                          f"(limit {self.tach_timeout:.2f} s)")
        if reading is None:
            return None
        self.last_reading_t = reading.t
        value = reading.value
        if reading.overload or not math.isfinite(value) or value < 0 or value > 2.0 * self.max_speed:
            raw = reading.raw.decode("latin-1", "replace").strip()
            raise Tripped(f"tachometer {self.tach.name} implausible reading {value!r} rad/s "
                          f"(overload={reading.overload}, raw {raw!r})")
        if value > self.overspeed:
            raise Tripped(f"over-speed on {self.name}: {value * 60 / (2 * math.pi):.0f} RPM > "
                          f"{self.overspeed * 60 / (2 * math.pi):.0f} RPM")
        return value

    def tick(self, t: float) -> LoopSnapshot:
        if self.started_at is None:
            self.started_at = t
        dt = self.period_s if self.last_t is None else max(0.0, t - self.last_t)
        self.last_t = t
        measured = self._measure(t)
        if self.plausibility is not None:
            plaus.advance(self.plausibility, self.plausible, t)
            reason = plaus.judge(self.plausibility, self.plausible, t, measured, self.last_reading_t,
                                 (self.tach.name, self.motor.name), self.gains.max_duty)
            if reason:
                raise Tripped(f"{self.name}: {reason}")
        self.setpoint = ramp_toward(self.setpoint, self.target, self.max_ramp, dt)
        if self.target > 0 and not self.enabled:
            self.motor.enable()
            self.enabled = True
        due = self.last_status_t is None or t - self.last_status_t >= self.status_period - 1e-9
        if self.enabled and due:  # right after enabling too: before any duty is sent
            self.last_status_t = t
            status = self.motor.status()
            if status.errors:
                raise Tripped(f"motor controller {self.motor.name} reports errors: "
                              f"{', '.join(sorted(status.errors))}")
            if self.plausibility is not None and measured is not None:
                reason = plaus.cross_check(self.plausibility, self.plausible, t, measured,
                                           status.speed_rad_s, (self.tach.name, self.motor.name))
                if reason:
                    raise Tripped(f"{self.name}: {reason}")
        if self.enabled:
            duty = pi_step(self.gains, self.state, self.setpoint,
                           measured if measured is not None else 0.0, dt)
            if not math.isfinite(duty):
                raise Tripped(f"{self.name}: controller output duty {duty!r} is not a finite number "
                              "(check kp, ki and full_speed in the rig file)")
            self.motor.set_duty(duty)
            if self.plausibility is not None:
                plaus.command(self.plausible, t, duty, duty >= self.gains.max_duty - 1e-9)
        error = (measured if measured is not None else math.inf) - self.target
        settled = self.setpoint == self.target and self.settle.update(t, error)
        self.snapshot = LoopSnapshot(t, self.target, self.setpoint, measured, self.state.duty, settled)
        return self.snapshot


class SpeedControl:
    """Runs the rig's speed loops on the clock; latches the first interlock and zeroes motors."""

    def __init__(self, clock: Any, loops: list[SpeedLoop], all_motors: list[MotorKind],
                 period_s: float, emit: Emit | None = None) -> None:
        self.clock = clock
        self.loops = {loop.name: loop for loop in loops}
        self.all_motors = all_motors
        self.period_s = period_s
        self.emit = emit or (lambda event: None)
        self.tripped: str | None = None
        self.tripped_at: float | None = None
        self.zero_requested = False
        self.zeroed_at: float | None = None
        self.stopped = False
        #: motors whose STOP could not be delivered: {name: reason}
        self.stop_failures: dict[str, str] = {}
        #: checked every tick; a returned reason trips the interlock (e.g. a recorder failed)
        self.guards: list[Callable[[], str | None]] = []
        self._lock = threading.RLock()
        self._job: Any = None

    # ---- life cycle -----------------------------------------------------------------------
    def start(self) -> None:
        if self._job is None:
            self._job = self.clock.every(self.period_s, self._tick, name="speed-control")

    def stop(self, reason: str = "end of protocol") -> None:
        """Stop the job and command every motor to zero (normal end or any exit path)."""
        with self._lock:
            self.stopped = True
            if self._job is not None:
                self._job.cancel()
                self._job = None
            for loop in self.loops.values():
                loop.target = loop.setpoint = 0.0
            self._zero_all()

    def _zero_all(self) -> list[str]:
        """Command every motor to zero; the ``name: reason`` of each STOP not delivered."""
        failed = []
        for motor in self.all_motors:
            name = motor.name
            problem = stop_motor(motor)
            if problem:
                self.stop_failures[name] = problem
                failed.append(f"{name}: {problem}")
            else:
                self.stop_failures.pop(name, None)
        return failed

    def trip(self, reason: str) -> None:
        """Interlock: every motor to zero now, latch ``reason``, emit an ``interlock`` event."""
        with self._lock:
            failed = self._zero_all()
            if self.tripped is None:
                self.tripped = reason
                self.tripped_at = self.clock.now()
                if self._job is not None:
                    self._job.cancel()
                    self._job = None
                self.emit(Interlock(t=self.tripped_at, reason=reason, stop_failed=tuple(failed)))

    def request_zero(self) -> None:
        """Ask for the safe state at the next control tick (first Ctrl-C); safe from a signal handler."""
        self.zero_requested = True
        if not self.clock.is_virtual and self._job is None:
            self._zero_all()

    def check(self) -> None:
        """Raise :class:`SafetyError` in the caller's thread if an interlock tripped.

        A check is a moment on the clock: it reads it first, so where the caller computed for
        long before it (a camera burst's analysis), a real-clock recording marks its stand-still
        here (``SESSION/clock.jsonl``), and a faithful replay stands still as long, its loop
        tripping meanwhile what the recorded one tripped, before this check
        (docs/decisions/0036-camera-frames-in-a-faithful-replay.md)."""
        self.clock.now()
        if self.tripped is not None:
            raise SafetyError(f"interlock: {self.tripped}; motors commanded to zero")

    # ---- the control period ---------------------------------------------------------------
    def _tick(self, t: float) -> None:
        with self._lock:
            if self.tripped is not None or self.stopped:
                return  # a tick that was already waiting when stop() ran must not touch the ports
            if self.zero_requested:
                if self.zeroed_at is None:
                    for loop in self.loops.values():
                        loop.target = loop.setpoint = 0.0
                    self._zero_all()
                    self.zeroed_at = t
                return
            try:
                for guard in self.guards:
                    problem = guard()
                    if problem:
                        raise Tripped(problem)
                for loop in self.loops.values():
                    loop.tick(t)
            except Tripped as exc:
                self.trip(str(exc))
            except LabkitError as exc:  # a device fault names device, command and bytes itself
                self.trip(str(exc))
            except Exception as exc:  # noqa: BLE001 - any fault in a tick is an interlock
                self.trip(f"control fault: {type(exc).__name__}: {exc}")

    # ---- used by the runner ---------------------------------------------------------------
    def set_targets(self, targets: dict[str, float]) -> None:
        with self._lock:
            self.check()
            for name in targets:
                if name not in self.loops:
                    raise SafetyError(f"no speed loop {name!r}; this rig has {', '.join(self.loops)}")
            for name, speed in targets.items():
                self.loops[name].set_target(speed)
        self.start()

    def suspect_since(self) -> float | None:
        """Start of a plausibility violation of any loop that has not tripped yet (None: none):
        readings taken after it may be from a faulty sensor until the verdict."""
        with self._lock:
            times = [s for loop in self.loops.values() if loop.plausibility is not None
                     and (s := loop.plausible.pending_since()) is not None]
            return min(times, default=None)

    def await_verdict(self, until: float, checkpoint: Callable[[], None],
                      each_period: Callable[[], None] = lambda: None) -> None:
        """Wait (in control periods, calling ``checkpoint``) while a plausibility violation that
        began at or before ``until`` is pending, so readings up to ``until`` become a point
        only once it has cleared: or it trips and ``checkpoint`` raises. Bounded by the
        longest a verdict can take."""
        waits = [max(p.hold_s, p.stuck_s) for loop in self.loops.values()
                 if (p := loop.plausibility) is not None]
        deadline = self.clock.now() + max(waits, default=0.0) + 2.0 * self.period_s
        while (since := self.suspect_since()) is not None and since <= until:
            checkpoint()
            if self.clock.now() >= deadline:
                return
            self.clock.sleep(self.period_s)
            each_period()

    def settled(self) -> bool:
        with self._lock:
            return all(loop.snapshot.settled for loop in self.loops.values())

    def snapshots(self) -> dict[str, LoopSnapshot]:
        with self._lock:
            return {name: loop.snapshot for name, loop in self.loops.items()}


def short_of_reach(loop: SpeedLoop) -> str | None:
    """Why ``loop`` cannot settle where it is: its duty at the cap and the rotor below the
    target, i.e. the motor gives all it may and tops out short of the target, or so close to
    the settle band's edge that its jitter keeps leaving the band (a target beyond this rig
    under its load); None otherwise."""
    s = loop.snapshot
    if s.measured_rad_s is None or s.duty < loop.gains.max_duty - 1e-6 or s.measured_rad_s >= s.target_rad_s:
        return None
    return (f"{loop.name}: the duty is at its cap {loop.gains.max_duty:.2f} and the rotor tops out at "
            f"{rad_s_to_rpm(s.measured_rad_s):.0f} RPM, "
            f"{rad_s_to_rpm(s.target_rad_s - s.measured_rad_s):.0f} RPM below the target (settle tolerance "
            f"{rad_s_to_rpm(loop.settle.tolerance):.0f} RPM): the motor cannot reach "
            f"{rad_s_to_rpm(s.target_rad_s):.0f} RPM under its load (lower the plan's top speed)")


def duty_cap(max_duty: float, max_speed_rad_s: float, full_speed_rad_s: float) -> float:
    """The highest duty a loop may command: the rig's ``max_duty``, and no more than the duty
    whose feed-forward speed ``duty * full_speed`` is the rig's ``max_speed``, so a tachometer
    that reads low cannot drive the rotor past the limit (docs/explanation/safety.md, "Sensor faults")."""
    if full_speed_rad_s <= 0:
        return max_duty
    return min(max_duty, max_speed_rad_s / full_speed_rad_s)


def unreachable_target(rig: Any, target_rad_s: float) -> str | None:
    """Why ``rig``'s loops cannot reach ``target_rad_s`` by the feed-forward (a likely typo in
    ``full_speed``), or None; checked with the plan, before anything starts."""
    c, lim = rig.control, rig.limits
    cap = duty_cap(lim.max_duty, lim.max_speed_rad_s, c.full_speed_rad_s)
    return plaus.unreachable(plausibility_settings(c), target_rad_s, cap)


def plausibility_settings(control: Any) -> plaus.PlausibilitySettings:
    """The rig's ``[control]`` plausibility keys (docs/reference/rig-files.md)."""
    return plaus.PlausibilitySettings(
        full_speed_rad_s=control.full_speed_rad_s, motor_tau_s=control.motor_tau_s,
        ratio=control.plausible_ratio, slack_rad_s=control.plausible_slack_rad_s,
        hold_s=control.plausible_hold_s, grace_s=control.spin_up_grace_s,
        stuck_s=control.tach_stuck_s, stall_s=control.stall_s)


def build_speed_control(open_rig: Any, clock: Any, emit: Emit | None = None,
                        loops: list[str] | None = None) -> SpeedControl:
    """Speed loops for ``open_rig`` as its rig file pairs them (``[control]``)."""
    rig = open_rig.rig
    c, lim = rig.control, rig.limits
    gains = PIGains(c.full_speed_rad_s, c.kp, c.ki,
                    duty_cap(lim.max_duty, lim.max_speed_rad_s, c.full_speed_rad_s))
    settings = plausibility_settings(c)
    built = []
    for cfg in c.loops:
        if loops is not None and cfg.name not in loops:
            continue
        built.append(SpeedLoop(
            cfg.name, _motor(open_rig, cfg.motor), _tachometer(open_rig, cfg.tach),
            period_s=c.period_s, gains=gains, max_speed_rad_s=lim.max_speed_rad_s,
            max_ramp_rad_s2=lim.max_ramp_rad_s2, overspeed_margin=lim.overspeed_margin,
            settle_tolerance_rad_s=c.settle_tolerance_rad_s, settle_hold_s=c.settle_hold_s,
            tach_timeout_s=c.tach_timeout_s, status_period_s=c.status_period_s,
            plausibility=settings))
    motors = [_motor(open_rig, role) for role in open_rig.motors()]
    return SpeedControl(clock, built, motors, c.period_s, emit)


def _motor(open_rig: Any, role: str) -> MotorKind:
    """The open driver ``role`` as a motor controller (labkit.devices.kinds.MotorKind)."""
    if isinstance(driver := open_rig.drivers[role], MotorKind):
        return driver
    raise _cannot_drive(open_rig, role, driver, "motor controller", "enable, set_duty, stop and status")


def _tachometer(open_rig: Any, role: str) -> TachometerKind:
    """The open driver ``role`` as a tachometer (labkit.devices.kinds.TachometerKind)."""
    if isinstance(driver := open_rig.drivers[role], TachometerKind):
        return driver
    raise _cannot_drive(open_rig, role, driver, "tachometer", "latest and readings_since")


def _cannot_drive(open_rig: Any, role: str, driver: object, what: str, needs: str) -> LabkitError:
    """A driver (a plugin's) that lacks a method its kind needs, named with its role and class."""
    return LabkitError(f"{open_rig.rig.path}: {role} ({type(driver).__name__}) cannot serve the speed loop "
                       f"as a {what}: it needs {needs}")
