"""The floating body's orientation over time: the unit normal of its polar face in the lab.

Lab frame: the magnet at the origin, its rest axis along +z, towards the screen. Two motions:

* :class:`PrecessionNutation`: a kinematic model with two rotating tilt components, a slow one
  (precession, ``A e^{i W t}``) and a fast one (nutation, ``B e^{i k W t}``), plus a constant
  mean tilt ``c``. Their sum is the trochoid of Eq. 6.38 (``k = (1 + a) / a``; ``k = -1`` is an
  ellipse, ``B = 0`` a circle). The components are the tangent-plane coordinates of the reflected
  beam, ``w = tan(2 tilt)`` along the tilt's azimuth, so the mirror law puts the spot on a
  perpendicular screen at distance ``L`` exactly on ``L w``: the pattern is an exact trochoid for
  any amplitude, and for small tilts ``w`` is twice the tilt vector (Sec. 5.2.3).
* :class:`SimulatedCone`: the orientation integrated by :mod:`labkit.sim` for a bundled scene
  (``conical_5_1``: the exact conical motion of Eq. 5.7/5.24), interpolated between samples.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np


def loops_ratio(kind: str, loops: int) -> int:
    """``k = (1 + a) / a`` of Eq. 6.38 for a pattern with ``loops`` loops (Sec. 6.5 counting: an
    epitrochoid's main loop plus its small loops, ``a = 1 / (loops - 1)``; a hypotrochoid's arms,
    ``a = -1 / loops``); an ellipse or circle is ``k = -1``."""
    if kind in ("circle", "ellipse"):
        return -1
    a = 1.0 / (loops - 1) if kind == "epitrochoid" else -1.0 / loops
    return int(round((1 + a) / a))


def normal_from_beam_tangent(w: np.ndarray) -> np.ndarray:
    """Polar-face normals (N, 3) that reflect a beam arriving along -z into the directions
    ``(w_x, w_y, 1)``: by the mirror law the normal bisects the reversed incoming beam and the
    reflected one."""
    w = np.atleast_2d(w)
    r = np.column_stack([w[:, 0], w[:, 1], np.ones(len(w))])
    r /= np.linalg.norm(r, axis=1, keepdims=True)
    n = r + np.array([0.0, 0.0, 1.0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


@dataclass(frozen=True)
class PrecessionNutation:
    """Tilt components (tangent of the reflected beam's angle, dimensionless): mean ``c``,
    precession ``A`` at ``cycle_hz``, nutation ``B`` at ``k * cycle_hz`` (complex numbers as
    ``(re, im)`` pairs, x + i y in the lab's xy plane); ``phase_rad`` at t = 0."""

    c: tuple[float, float]
    A: tuple[float, float]
    B: tuple[float, float]
    k: int
    cycle_hz: float
    phase_rad: float = 0.0

    def beam_tangent(self, t: np.ndarray) -> np.ndarray:
        """``c + A e^{i s} + B e^{i k s}``, ``s = 2 pi f t + phase`` as (N, 2)."""
        s = 2 * math.pi * self.cycle_hz * np.asarray(t, dtype=float) + self.phase_rad
        z = complex(*self.c) + complex(*self.A) * np.exp(1j * s) + complex(*self.B) * np.exp(1j * self.k * s)
        return np.column_stack([z.real, z.imag])

    def normals(self, t: np.ndarray) -> np.ndarray:
        return normal_from_beam_tangent(self.beam_tangent(t))

    def tilt_rad(self, t: np.ndarray) -> np.ndarray:
        """The body's tilt from the rest axis (half the beam's deflection)."""
        w = self.beam_tangent(t)
        return 0.5 * np.arctan(np.hypot(w[:, 0], w[:, 1]))


@functools.lru_cache(maxsize=4)
def _simulated(scene_name: str, cycles: int, samples_per_period: int):
    from labkit.sim import load_scene, simulate

    scene = load_scene(scene_name)
    result = simulate(scene, cycles=cycles, samples_per_period=samples_per_period)
    if result.status != "ok":
        raise RuntimeError(f"simulation of {scene_name} ended with status {result.status}")
    axis = np.asarray(scene.bodies[0].moment_Am2, dtype=float)
    axis /= np.linalg.norm(axis)
    normals = result.dipole_directions(0, axis)
    period = float(result.times_s[1] - result.times_s[0]) * samples_per_period
    return np.asarray(result.times_s, dtype=float), normals, period


@functools.lru_cache(maxsize=4)
def _spline(scene_name: str, cycles: int, samples_per_period: int):
    """Cubic spline through the simulated normals (error ~ (2 pi / samples)^4: < 1e-8 rad)."""
    from scipy.interpolate import CubicSpline

    times, normals, _ = _simulated(scene_name, cycles, samples_per_period)
    return CubicSpline(times, normals, axis=0)


@dataclass(frozen=True)
class SimulatedCone:
    """The dipole axis of the first body of a :mod:`labkit.sim` scene. The simulated motion is
    periodic with the drive; ``cycle_hz`` rescales its period (the video sees ``cycle_hz`` drive
    cycles per second), ``phase_cycles`` shifts it. ``cycles`` simulated periods are kept and
    repeated (the conical scene's motion is exactly periodic)."""

    scene: str = "conical_5_1"
    cycle_hz: float = 40.0
    phase_cycles: float = 0.0
    cycles: int = 4
    samples_per_period: int = 64

    def _table(self):
        return _simulated(self.scene, self.cycles, self.samples_per_period)

    def normals(self, t: np.ndarray) -> np.ndarray:
        spline, start, period = self._spline()
        u = (np.asarray(t, dtype=float) * self.cycle_hz + self.phase_cycles) % 1.0  # drive cycles
        n = spline(start + u * period)  # in the last simulated period: transients, if any, settled
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def _spline(self):
        times, normals, period = self._table()
        return _spline(self.scene, self.cycles, self.samples_per_period), times[-1] - period, period

    def simulated_period_s(self) -> float:
        return self._table()[2]

    def tilt_rad(self, t: np.ndarray) -> np.ndarray:
        return np.arccos(np.clip(self.normals(t)[:, 2], -1, 1))
