"""The physics behind the emulators: the plant of one emulated rig.

Every emulator of a rig reads and writes the same :class:`RigPlant`, so the balance sees the
PFR force of the speed the motor emulator has reached, and the spin tachometer sees the
floator spin. State is advanced lazily and analytically to the time asked for, so the
plant is exact on any clock and costs nothing between reads.

Plain plants type in the paper's fitted laws: the balance force of Fig. 5.25,
``grams = 224e6 * rpm**-1.9`` (a PFR force falling roughly as omega^-2, Eq. 5.81). The model
plant (:mod:`labkit.emulators.model_plant`, docs/explanation/twin.md) derives both from the rig file's
magnets.

The spin-critical plant of Fig. 6.18 (:class:`FloatorPlant`, :func:`fig618_plant`): a floator
held in the bound state spins up about its dipole axis and drops when its spin reaches the
critical spin of Eq. 6.37 (Eq. 5.69 with the paper's extra term), with seeded noise.
"""

from __future__ import annotations

import math
import random
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from labkit.units import G0, RAD_S_PER_RPM


def fig525_force_n(speed_rad_s: float, a: float = 224e6, b: float = -1.9,
                   min_rpm: float = 3000.0) -> float:
    """PFR force (N) of Fig. 5.25's fit y[g] = a * x[rpm]**b; 0 below ``min_rpm`` (no bound state)."""
    rpm = abs(speed_rad_s) / RAD_S_PER_RPM
    if rpm < min_rpm:
        return 0.0
    return a * rpm**b * 1e-3 * G0


@dataclass
class MotorPlant:
    """First-order speed response to duty: d(omega)/dt = (duty*max_speed - load - omega)/tau."""

    max_speed_rad_s: float = 2500.0   # speed at duty 1 with no load (~24 000 RPM)
    tau_s: float = 0.4                # mechanical time constant
    load_rad_s: float = 0.0           # speed lost to load (friction, air)
    duty: float = 0.0
    speed_rad_s: float = 0.0
    t: float = 0.0
    #: (time, duty) of every change of commanded duty, newest last (bounded); for tests and logs
    duty_changes: list[tuple[float, float]] = field(default_factory=list)

    #: clock time at which the controller's own command timeout will zero the duty unless a
    #: command re-arms it (set by motor emulators): the timeout then acts even while nobody
    #: talks to the controller's port (an emulator only runs when its port is used)
    watchdog_at: float | None = None
    #: clock time from which the motor does not follow its command (jammed: it stops whatever
    #: the duty); set by a motor emulator's ``stall_at`` fault
    stalled_at: float | None = None

    def advance(self, t: float) -> None:
        if self.watchdog_at is not None and t >= self.watchdog_at:
            at = max(self.watchdog_at, self.t)
            self.watchdog_at = None
            self.set_duty(0.0, at)
        if self.stalled_at is not None and self.t < self.stalled_at < t:
            self._relax(self.stalled_at)
        self._relax(t)

    @property
    def drive_duty(self) -> float:
        """The duty that moves the rotor: the commanded one, 0 once the motor has stalled."""
        stalled = self.stalled_at is not None and self.t >= self.stalled_at
        return 0.0 if stalled else self.duty

    def _relax(self, t: float) -> None:
        if t <= self.t:
            return
        target = self.drive_duty * self.max_speed_rad_s
        if target > 0:
            target = max(0.0, target - self.load_rad_s)
        elif target < 0:
            target = min(0.0, target + self.load_rad_s)
        decay = math.exp(-(t - self.t) / self.tau_s)
        self.speed_rad_s = target + (self.speed_rad_s - target) * decay
        self.t = t

    def set_duty(self, duty: float, t: float) -> None:
        self.advance(t)
        duty = max(-1.0, min(1.0, duty))
        if duty != self.duty:
            self.duty_changes.append((t, duty))
            del self.duty_changes[:-1000]
        self.duty = duty

    def zeroed_since(self, t: float) -> float | None:
        """When the duty was last set to zero at or after ``t`` and stayed there (None if not)."""
        if self.duty != 0.0:
            return None
        for when, duty in reversed(self.duty_changes):
            if duty == 0.0 and when >= t:
                return when
            if when < t:
                break
        return None


@dataclass(frozen=True)
class SpinCriticalLaw:
    """Eq. 6.37: ``-k w^2 = C (1 - w/w_ref)`` with ``k = v/w - 1`` (w rotor, v floator spin).

    Solved for the spin at which the bound state breaks:
    ``v_crit(w) = w - C (1 - w/w_ref) / w``. The paper fits C = 4.7e5 (series 1, a 15 mm
    sphere) and 6.63e5 (series 2) with w_ref = 3000 rad/s.
    """

    c: float = 4.7e5
    w_ref_rad_s: float = 3000.0

    def critical_spin(self, w: float) -> float:
        """Spin (rad/s) at which the floator drops at rotor speed ``w`` (rad/s); < 0: cannot trap."""
        if w <= 0:
            return -math.inf
        return w - self.c * (1.0 - w / self.w_ref_rad_s) / w

    def min_trap_speed(self) -> float:
        """Lowest rotor speed holding a floator without spin (v_crit = 0): w^2 + C w / w_ref - C = 0."""
        b = self.c / self.w_ref_rad_s
        return (-b + math.sqrt(b * b + 4.0 * self.c)) / 2.0


@dataclass
class FloatorPlant:
    """A floator held by the rotor (Fig. 6.18 set-up), its spin and its drop.

    While held, the spin relaxes toward ``spin_ratio * w`` with time constant
    ``spin_tau_s`` (the small torque of Sec. 6.5 that spins it up). It drops when the
    spin reaches ``v_crit(w) * (1 + e)``, e ~ N(0, ``noise_rel``) drawn (seeded) each time
    it is placed; or at once when the rotor is too slow to trap it. ``reload_s`` after a
    drop the "operator" places it again with zero spin (only if the rotor can hold it).
    """

    law: SpinCriticalLaw = field(default_factory=SpinCriticalLaw)
    mass_kg: float = 13.36e-3
    spin_ratio: float = 0.95
    spin_tau_s: float = 6.0
    noise_rel: float = 0.01
    reload_s: float = 2.0
    step_s: float = 0.01
    seed: int = 0
    present: bool = False
    spin_rad_s: float = 0.0
    t: float = 0.0
    drops: int = 0
    dropped_at: float | None = None
    _threshold: float = 1.0

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)

    def _place(self, t: float, w: float) -> None:
        if self.law.critical_spin(w) > 0:
            self.present, self.spin_rad_s = True, 0.0
            self._threshold = 1.0 + self.rng.gauss(0.0, self.noise_rel)
        self.dropped_at = None if self.present else t

    def advance(self, t: float, rotor_speed: Callable[[float], float]) -> None:
        """Advance to time ``t``; ``rotor_speed(t)`` is the rotor's angular speed (rad/s)."""
        while self.t < t:
            t1 = min(t, self.t + self.step_s)
            w = rotor_speed(t1)
            if self.present:
                target = self.spin_ratio * w
                decay = math.exp(-(t1 - self.t) / self.spin_tau_s)
                self.spin_rad_s = target + (self.spin_rad_s - target) * decay
                if self.spin_rad_s >= self.law.critical_spin(w) * self._threshold:
                    self.present, self.drops, self.dropped_at = False, self.drops + 1, t1
            else:
                if self.dropped_at is None:
                    self.dropped_at = t1
                if t1 - self.dropped_at >= self.reload_s:
                    self._place(t1, w)
            self.t = t1


@dataclass
class RigPlant:
    """Shared state of an emulated rig: motors by name, the PFR force, the floator's spin.

    ``force_law(speed_rad_s) -> N`` gives the force the balance sees from the ``"rotor"``
    motor. ``spin_*`` describe the floator of the Fig. 6.18 set-up; the spin-critical plant
    in :mod:`labkit.protocols` may replace ``spin_rate`` and ``drop_condition``.
    """

    seed: int = 0
    force_law: Callable[[float], float] = fig525_force_n
    motors: dict[str, MotorPlant] = field(default_factory=dict)
    floator_spin_rad_s: float = 0.0
    floator_present: bool = True
    #: the spin-critical floator (Fig. 6.18); None: constant spin, force from ``force_law``
    floator: FloatorPlant | None = None
    #: strobe emulators on this plant by role: the emulated camera lights the floator with
    #: their flashes (``sim://camera?scene=strobe``, :mod:`labkit.emulators.camera_strobe`)
    strobes: dict[str, Any] = field(default_factory=dict)
    _lock: threading.RLock = field(default_factory=threading.RLock, repr=False)

    def motor(self, name: str = "rotor") -> MotorPlant:
        with self._lock:
            if name not in self.motors:
                self.motors[name] = MotorPlant()
            return self.motors[name]

    def speed(self, t: float, name: str = "rotor") -> float:
        with self._lock:
            m = self.motor(name)
            m.advance(t)
            return m.speed_rad_s

    def set_duty(self, duty: float, t: float, name: str = "rotor") -> None:
        with self._lock:
            self.motor(name).set_duty(duty, t)

    def floator_spin(self, t: float) -> float:
        """Spin of the floating magnet about its dipole axis (rad/s) at time t.

        Placeholder dynamics (constant); the spin-critical plant (Fig. 6.18) replaces it.
        Returns 0 when the floator has dropped (no target for the spin tachometer).
        """
        with self._lock:
            self._advance_floator(t)
            return self.floator_spin_rad_s if self.floator_present else 0.0

    def tach_reading(self, t: float, source: str = "rotor") -> float:
        """What a tachometer aimed at ``source`` reads (rad/s): the floator's spin for
        ``"floator"``, else the named motor's speed (exact here; the model plant adds jitter
        and dropped pulses)."""
        if source == "floator":
            return self.floator_spin(t)
        return self.speed(t, source)

    def _advance_floator(self, t: float) -> None:
        if self.floator is None:
            return
        self.floator.advance(t, lambda tt: self.speed(tt))
        self.floator_present = self.floator.present
        self.floator_spin_rad_s = self.floator.spin_rad_s

    def force(self, t: float) -> float:
        """The force (N, upward on the rotor = downward on the balance pan) at time t."""
        with self._lock:
            if self.floator is not None:
                # balance under the rotator: it carries the held floator's weight (Eq. 6.33)
                self._advance_floator(t)
                return self.floator.mass_kg * G0 if self.floator.present else 0.0
            if not self.floator_present:
                return 0.0
            return self.force_law(self.speed(t))


def fig618_plant(seed: int = 0) -> RigPlant:
    """The spin-critical rig of Fig. 6.18 (series 1: 15 mm sphere, 13.36 g, C = 4.7e5)."""
    return RigPlant(seed=seed, floator=FloatorPlant(seed=seed))
