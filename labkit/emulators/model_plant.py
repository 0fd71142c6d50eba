"""The model plant: a virtual twin of a rig file, with a real rig's imperfections.

Presets ``model-fig525`` (balance force of the Fig. 5.25 set-up) and ``model-fig618``
(spin-up and drop of Fig. 6.18) derive what the emulated instruments see from the rig file's
magnets and geometry (:mod:`labkit.emulators.twin_model`), where the presets ``fig525`` and
``fig618`` type in the paper's fitted laws. Seeded imperfection knobs (docs/explanation/twin.md):

* ``vibration_g`` - the rotor's unbalance shakes the balance: a force ``vibration_g *
  (w / w_vib_ref)^2 * sin(w t + phase)`` on top of the PFR, sampled by the load cell (it
  aliases into noise). Balance noise, drift and creep are the balance emulator's own knobs
  (``noise_g``, ``drift_g_per_s``, ``creep`` in its sim:// URL).
* ``tach_jitter_rel`` - Gaussian relative jitter of every tachometer reading;
  ``tach_drop_p`` - probability that a reading misses one pulse of its gate
  (``tach_pulses_per_rev``, ``tach_gate_s``), so it reads ``(1 - 1/n)`` low.
* ``motor_tau_s``, ``motor_drag`` - first-order motor response and an air-drag load
  ``drag * w^2`` (rad/s lost at speed w) that the speed loop must make up.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

from labkit.emulators.break_up import break_up
from labkit.emulators.rig_plant import FloatorPlant, MotorPlant, RigPlant, SpinCriticalLaw
from labkit.emulators.twin_model import TwinParams, balance_force_table, default_params
from labkit.units import G0


@dataclass
class ModelMotor(MotorPlant):
    """:class:`MotorPlant` whose steady speed at duty d solves ``w = d w_max - drag w^2``."""

    drag: float = 0.0

    def _relax(self, t: float) -> None:
        if t <= self.t:
            return
        drive = self.drive_duty * self.max_speed_rad_s
        target = abs(drive)
        if self.drag > 0 and target > 0:
            target = (-1.0 + math.sqrt(1.0 + 4.0 * self.drag * target)) / (2.0 * self.drag)
        target = math.copysign(max(0.0, target - self.load_rad_s), drive) if drive else 0.0
        decay = math.exp(-(t - self.t) / self.tau_s)
        self.speed_rad_s = target + (self.speed_rad_s - target) * decay
        self.t = t


@dataclass
class Imperfections:
    """Seeded imperfections of a model plant (defaults: a decent lab rig)."""

    vibration_g: float = 0.01           # balance shake at w_vib_ref (grams-force amplitude)
    w_vib_ref_rad_s: float = 1047.2     # 10 000 RPM
    tach_jitter_rel: float = 2e-4
    tach_drop_p: float = 0.002
    tach_pulses_per_rev: int = 2
    tach_gate_s: float = 0.05
    motor_tau_s: float = 0.4
    motor_drag: float = 1.2e-5          # 3 % of the free speed lost at 24 000 RPM


@dataclass
class ModelPlant(RigPlant):
    """A :class:`RigPlant` whose balance force and floator come from the model of ``params``."""

    params: TwinParams = field(default_factory=TwinParams)
    imperfections: Imperfections = field(default_factory=Imperfections)
    preset: str = "model-fig525"

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed * 104729 + 17)
        self.vib_phase = self.rng.uniform(0.0, 2.0 * math.pi)
        self.table = balance_force_table(self.params)
        self.force_law = self.table.force_n

    def motor(self, name: str = "rotor") -> MotorPlant:
        with self._lock:
            if name not in self.motors:
                imp = self.imperfections
                self.motors[name] = ModelMotor(tau_s=imp.motor_tau_s, drag=imp.motor_drag)
            return self.motors[name]

    def force(self, t: float) -> float:
        """PFR from the model table (or the held floator's weight) plus the rotor's shake."""
        with self._lock:
            base = super().force(t)
            w = self.speed(t)
            imp = self.imperfections
            shake = imp.vibration_g * 1e-3 * G0 * (w / imp.w_vib_ref_rad_s) ** 2
            return base + shake * math.sin(w * t + self.vib_phase)

    def tach_reading(self, t: float, source: str = "rotor") -> float:
        """What a tachometer reads of ``source``: the true speed with jitter and dropped pulses."""
        with self._lock:
            true = super().tach_reading(t, source)
            imp = self.imperfections
            reading = true * (1.0 + self.rng.gauss(0.0, imp.tach_jitter_rel))
            if true > 0 and self.rng.random() < imp.tach_drop_p:
                pulses = abs(true) / (2.0 * math.pi) * imp.tach_pulses_per_rev * imp.tach_gate_s
                reading *= 1.0 - 1.0 / max(pulses, 1.0)
            return reading

    def model_force_n(self, omega: float) -> float:
        """The model's balance force (N) at ``omega`` without imperfections (for comparisons)."""
        return self.table.force_n(omega)


def model_plant(preset: str, seed: int = 0, params: TwinParams | None = None,
                imperfections: Imperfections | None = None) -> ModelPlant:
    """A model plant: ``model-fig525`` (balance force) or ``model-fig618`` (spin-critical, C of
    Eq. 6.37 from :func:`labkit.emulators.break_up.break_up`: derived from the magnets, or from
    the rig file's ``break_phi_rad`` when it gives one)."""
    p = params or default_params(preset)
    plant = ModelPlant(seed=seed, params=p, imperfections=imperfections or Imperfections(), preset=preset)
    if preset == "model-fig618":
        law = SpinCriticalLaw(c=break_up(p).c)
        plant.floator = FloatorPlant(law=law, mass_kg=p.mass_kg, seed=seed)
    return plant


MODEL_PRESETS = ("model-fig525", "model-fig618")
