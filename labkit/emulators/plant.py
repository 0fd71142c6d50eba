"""The physics behind the emulators: one seeded plant per emulated rig.

Every emulator of a rig reads and writes the same :class:`RigPlant`, so the balance sees the
PFR force of the speed the motor emulator has reached, and the spin tachometer sees the
floator spin. State is advanced lazily and analytically to the time asked for, so the
plant is exact on any clock and costs nothing between reads.

Defaults follow the paper: the balance force is the fitted law of Fig. 5.25,
``grams = 224e6 * rpm**-1.9`` (a PFR force falling roughly as omega^-2, Eq. 5.81).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

G0 = 9.80665  # m/s^2, standard gravity: grams-force -> newtons
RAD_S_PER_RPM = 2.0 * math.pi / 60.0


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

    def advance(self, t: float) -> None:
        if t <= self.t:
            return
        target = self.duty * self.max_speed_rad_s
        if target > 0:
            target = max(0.0, target - self.load_rad_s)
        elif target < 0:
            target = min(0.0, target + self.load_rad_s)
        decay = math.exp(-(t - self.t) / self.tau_s)
        self.speed_rad_s = target + (self.speed_rad_s - target) * decay
        self.t = t

    def set_duty(self, duty: float, t: float) -> None:
        self.advance(t)
        self.duty = max(-1.0, min(1.0, duty))


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
            return self.floator_spin_rad_s if self.floator_present else 0.0

    def force(self, t: float) -> float:
        """The force (N, upward on the rotor = downward on the balance pan) at time t."""
        with self._lock:
            if not self.floator_present:
                return 0.0
            return self.force_law(self.speed(t))


_PLANTS: dict[str, RigPlant] = {}
_PLANTS_LOCK = threading.Lock()


def shared_plant(name: str, seed: int = 0) -> RigPlant:
    """The process-wide plant called ``name`` (created on first use), shared by sim:// ports."""
    with _PLANTS_LOCK:
        if name not in _PLANTS:
            _PLANTS[name] = RigPlant(seed=seed)
        return _PLANTS[name]


def reset_plants() -> None:
    """Forget all shared plants (tests)."""
    with _PLANTS_LOCK:
        _PLANTS.clear()
