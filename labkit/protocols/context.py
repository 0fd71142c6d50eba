"""What a protocol's step may do: :class:`RunContext`, the verbs ``set``, ``settle``,
``record``, ``sleep`` and ``checkpoint`` and the devices handed out by kind
(:mod:`labkit.devices.kinds`). Every wait polls the interlocks and is a checkpoint; readings
are emitted once per stream with a descriptor (docs/decisions/0033-one-reading-shape.md).

The :class:`~labkit.protocols.runner.Runner` makes one per run and hands it to every step.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from labkit import documents as doc
from labkit.control.loop import SpeedControl, short_of_reach
from labkit.devices.base import Device
from labkit.devices.kinds import (
    BalanceKind,
    CameraKind,
    MotorKind,
    MotorStatusKind,
    StrobeKind,
    TachometerKind,
)
from labkit.errors import LabkitError
from labkit.protocols.events import not_logged
from labkit.readings import Reading
from labkit.units import rad_s_to_rpm

if TYPE_CHECKING:
    from labkit.protocols.definition import Step
    from labkit.protocols.runner import Runner

CONTROL_EVENT_INTERVAL_S = 0.25


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
                state = ", ".join(  # the duty too: at 1.00 the motor gives all it has there
                    f"{n}: target {rad_s_to_rpm(s.target_rad_s):.0f} RPM, measured "
                    + ("none" if s.measured_rad_s is None else f"{rad_s_to_rpm(s.measured_rad_s):.0f} RPM")
                    + f", duty {s.duty:.2f}" for n, s in snaps.items())
                beyond = [why for loop in self.control.loops.values() if (why := short_of_reach(loop))]
                raise LabkitError(f"speed did not settle within {timeout:.0f} s ({state}); motors at zero"
                                  + "".join(f"; {why}" for why in beyond))
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
