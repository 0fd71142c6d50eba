"""The stroboscope's body motion as :mod:`labkit.sim` integrates it (docs/explanation/robustness-suite.md,
*What the renderer models*).

:class:`SimulatedSwing` stands in for the kinematic :class:`~labkit.footage.strobe_scene.Swing`
(Eq. 5.97 with a sinusoidal tilt). It takes a free floator bound beneath a spinning rotator (point
dipoles, gravity on): the co-rotating steady state of :mod:`labkit.predict` (cone plus lateral
circle, Sec. 5.2, Eq. 5.62) is the initial state of a :mod:`labkit.sim` run of a few drive periods,
and the last period is kept. The camera looks along the lab's y axis, so the image shows:

* the tilt ``theta = atan2(n_x, n_z)`` of the floator's dipole axis ``n`` from the rotor axis, the
  projection of the cone (its amplitude is the cone angle phi);
* the centre of mass across the rotor axis, ``x`` in pixels (its amplitude is the lateral circle's
  radius beta).

The motion is exactly periodic with the drive (the steady state); the run checks that two
consecutive simulated periods agree. The truth amplitudes are the first-harmonic amplitudes of
``theta`` and ``x`` at the rotor frequency (what the analysis's sine model measures; they differ
from the cone angle and beta by the cone's small third harmonic, < 0.2 % here), and the RC offset is
``delta = beta / tan(phi)`` (Eq. 5.97). The rotor speed is the clip's own ``rotor_hz``: the steady
state is solved at that speed, so phi and beta are those of the model at that speed.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

SIM_PERIODS = 4  # simulated drive periods; the last one is kept
PERIODIC_TOL_RAD = 1e-6  # largest tilt change between the last two periods


class SimulatedSwingError(ValueError):
    """The magnet pair does not bind at the requested speed, or the run is not periodic."""


@functools.lru_cache(maxsize=16)
def _one_period(rotator: str, floator: str, tilt_deg: float, speed_rpm: float,
                samples: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Tilt (rad, rest axis removed) and lateral centre of mass (m) over one drive period at
    ``samples`` equally spaced drive phases starting at phase 0, and the run's period (s)."""
    from labkit.predict.magnets import parse_magnet_spec
    from labkit.predict.pair import ForceCurve, Pair
    from labkit.predict.verify import build_scene
    from labkit.sim import scene_from_dict, simulate

    pair = Pair(parse_magnet_spec(rotator), parse_magnet_spec(floator), math.radians(tilt_deg))
    omega = speed_rpm / 60.0 * 2 * math.pi
    curve = ForceCurve(pair, omega)
    bound = curve.bound_state()
    if not bound.bound:
        raise SimulatedSwingError(f"{floator} under {rotator} at {speed_rpm:.0f} RPM: not bound "
                                  f"({bound.reason})")
    scene = scene_from_dict(build_scene(pair, omega, curve.state(bound.r_eq), SIM_PERIODS, 0.0),
                            source="<footage>")
    result = simulate(scene, cycles=SIM_PERIODS, samples_per_period=samples)
    if result.status != "ok":
        raise SimulatedSwingError(f"simulation ended with status {result.status}")
    n = result.axes[:, 0]  # the floator's dipole axis (an axisymmetric body keeps only its axis)
    theta = np.arctan2(n[:, 0], np.abs(n[:, 2]))
    x = result.positions_m[:, 0, 0]
    last, before = slice(-samples - 1, -1), slice(-2 * samples - 1, -samples - 1)
    drift = float(np.max(np.abs(theta[last] - theta[before])))
    if drift > PERIODIC_TOL_RAD:
        raise SimulatedSwingError(f"the simulated motion is not periodic (tilt changes by {drift:.2g} rad "
                                  "per period)")
    theta, x = theta[last], x[last]
    return theta - theta.mean(), x - x.mean(), 2 * math.pi / omega


def first_harmonic(values: np.ndarray) -> complex:
    """Complex amplitude ``c`` of ``values`` sampled over one period: ``values ~ Re(c e^{i psi})``."""
    return 2.0 * complex(np.fft.rfft(values)[1]) / len(values)


@dataclass(frozen=True)
class SimulatedSwing:
    """A free floator bound beneath a spinning rotator, integrated by labkit.sim, seen side on.

    ``rotator``, ``floator``: magnet specs as for ``labkit predict`` (e.g. ``cylinder:6x3mm``);
    ``tilt_deg``: the rotator magnet's tilt gamma (Eq. 5.25); ``rotor_hz``: the rotor speed;
    ``mm_per_px``: the image scale; ``psi0_rad``: the drive phase at t = 0."""

    rotator: str = "cylinder:6x3mm"
    floator: str = "cylinder:8x8mm"
    tilt_deg: float = 10.0
    rotor_hz: float = 250.0
    mm_per_px: float = 0.13
    psi0_rad: float = 0.0
    samples: int = 256

    def _period(self) -> tuple[np.ndarray, np.ndarray, float]:
        return _one_period(self.rotator, self.floator, self.tilt_deg, 60.0 * self.rotor_hz, self.samples)

    def psi(self, t: np.ndarray | float) -> np.ndarray:
        return 2 * math.pi * self.rotor_hz * np.asarray(t, dtype=float) + self.psi0_rad

    def _at(self, values: np.ndarray, t: np.ndarray | float) -> np.ndarray:
        """Periodic linear interpolation of one period's samples (256 per period: error < 1e-5 phi)."""
        u = (self.psi(t) / (2 * math.pi)) % 1.0 * len(values)
        i = np.floor(u).astype(int) % len(values)
        f = u - np.floor(u)
        return values[i] * (1 - f) + values[(i + 1) % len(values)] * f

    def tilt(self, t: np.ndarray | float) -> np.ndarray:
        return self._at(self._period()[0], t)

    def lateral_px(self, t: np.ndarray | float) -> np.ndarray:
        return self._at(self._period()[1], t) * 1e3 / self.mm_per_px

    @property
    def phi_rad(self) -> float:
        """First-harmonic amplitude of the tilt (the cone angle within its third harmonic)."""
        return abs(first_harmonic(self._period()[0]))

    @property
    def beta_px(self) -> float:
        """First-harmonic amplitude of the centre of mass across the rotor axis, in pixels."""
        return abs(first_harmonic(self._period()[1])) * 1e3 / self.mm_per_px

    @property
    def delta_px(self) -> float:
        """The RC offset beta / tan(phi) of Eq. 5.97, signed as the kinematic Swing's: the lateral
        motion is ``-delta tan(theta)`` when it runs in phase with ``-theta``."""
        in_phase = abs(self.lag_rad) < math.pi / 2
        return (-1.0 if in_phase else 1.0) * self.beta_px / math.tan(self.phi_rad)

    @property
    def lag_rad(self) -> float:
        """Phase of the lateral motion against the tilt (0 or pi for Eq. 5.97's rigid swing)."""
        theta_c, x_c = first_harmonic(self._period()[0]), first_harmonic(self._period()[1])
        return float(np.angle(x_c * theta_c.conjugate()))
