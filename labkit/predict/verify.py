"""Time-domain check of a predicted bound state with :mod:`labkit.sim`.

A free floator (gravity on) starts on the predicted equilibrium distance on the axis of the
driven, tilted rotator, on the paper's conical equilibrium (Eq. 5.12/5.35 via the scene helper)
and with a small sideways push. The run must end ``ok`` (no contact, no escape, invariant
drift below the threshold) and stay near the predicted distance. The mean distance checks the
steady-state solve; the oscillations give the stiffnesses: the axial and lateral frequencies
of the cycle-averaged motion, k = m w^2 (the lateral one is the only estimate of the lateral
stiffness: the frozen-motion force obeys Earnshaw's theorem and would say nothing useful).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from labkit.model.floator_equilibrium import FloatorState, lab_initial_state
from labkit.predict.pair import Pair
from labkit.sim import scene_from_dict, simulate


@dataclass(frozen=True)
class Oscillation:
    """Angular frequencies (rad/s) of a cycle-averaged motion and the stiffness they imply.

    ``stiffness`` is m w^2 for the axial motion and m w+ w- for the lateral one (forward and
    backward whirl of x + i y: for m z'' + i G z' + k z = 0 the two roots multiply to k/m);
    ``error`` is the change of the stiffness when only the first half of the run is analysed
    (a halving check, which also covers the spectral resolution).
    """

    frequencies: tuple[float, ...]
    stiffness: float
    error: float


def _peak(spectrum: np.ndarray, freqs: np.ndarray) -> float:
    """Frequency of the largest bin, refined by a parabola through its neighbours."""
    i = int(np.argmax(spectrum))
    if 0 < i < len(spectrum) - 1:
        a, b, c = np.log(spectrum[i - 1: i + 2] + 1e-300)
        denom = a - 2 * b + c
        shift = 0.5 * (a - c) / denom if denom != 0 else 0.0
        return float(freqs[i] + shift * (freqs[1] - freqs[0]))
    return float(freqs[i])


def _whirl(z: np.ndarray, dt: float, mass: float, lateral: bool) -> tuple[tuple[float, ...], float]:
    z = z - np.mean(z)
    n = len(z)
    if n < 16:
        return (), math.nan
    window = np.hanning(n)
    spec = np.abs(np.fft.fft(z * window))
    freqs = 2 * np.pi * np.fft.fftfreq(n, dt)
    pos = freqs > 0
    w_pos = _peak(spec[pos], freqs[pos])
    if not lateral:
        return (w_pos,), mass * w_pos**2
    neg = freqs < 0
    order = np.argsort(freqs[neg])
    w_neg = -_peak(spec[neg][order], freqs[neg][order])
    return (w_pos, -w_neg), mass * w_pos * w_neg


def oscillation(z: np.ndarray, dt: float, mass: float, lateral: bool) -> Oscillation:
    """Axial (real ``z``) or lateral (complex ``x + i y``) oscillation of a series sampled every
    ``dt`` (see :class:`Oscillation`)."""
    freqs, k = _whirl(z, dt, mass, lateral)
    _, k_half = _whirl(z[: len(z) // 2], dt, mass, lateral)
    return Oscillation(freqs, k, abs(k - k_half))


@dataclass(frozen=True)
class VerifyResult:
    status: str
    status_detail: str
    cycles: int
    bound: bool
    distance_mean_m: float
    distance_min_m: float
    distance_max_m: float
    invariant: str
    invariant_drift: float
    axial: Oscillation
    lateral: Oscillation
    wall_s: float
    compile_s: float


def _rotation_with_z(axis: np.ndarray) -> np.ndarray:
    """A proper rotation whose third column (body z) is the unit vector ``axis``."""
    z = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def build_scene(pair: Pair, omega: float, state: FloatorState, cycles: int, push_m_s: float) -> dict:
    """Scene (a dict for :func:`labkit.sim.scene_from_dict`) starting on the co-rotating steady
    state ``state`` (cone and lateral circle), inverted through the rotator when the floator
    hangs beneath it, plus a sideways push ``push_m_s``."""
    f, rot = pair.floator, pair.rotator
    init = lab_initial_state(pair.setup(omega), state)
    sign = -1.0 if pair.placement == "beneath" else 1.0
    velocity = sign * init["velocity"] + np.array([push_m_s, 0.0, 0.0])
    return {
        "scene": {"name": "predict", "cycles": cycles},
        "rotator": [{
            "name": "rotator", "moment_Am2": rot.moment_a_m2, "omega_rad_s": omega,
            "tilt_rad": pair.gamma, "radius_m": rot.axial_half_extent_m,
        }],
        "body": [{
            "name": "floator", "mass_kg": f.mass_kg,
            "inertia_kg_m2": [f.inertia_radial_kg_m2, f.inertia_radial_kg_m2, f.inertia_axial_kg_m2],
            "moment_Am2": f.moment_a_m2,
            "shape": {"kind": "sphere", "radius_m": f.axial_half_extent_m},
            "initial": {
                "position_m": (sign * init["position"]).tolist(),
                "velocity_m_s": velocity.tolist(),
                "rotation_matrix": _rotation_with_z(init["dipole_axis"]).tolist(),
                "angular_velocity_rad_s": init["angular_velocity"].tolist(),
            },
        }],
        "gravity": {"g_m_s2": [0.0, 0.0, -pair.gravity]},
    }


def verify(pair: Pair, omega: float, state: FloatorState, cycles: int = 400, push_fraction: float = 0.01,
           drift_threshold: float = 1e-6, tolerance: float = 0.25) -> VerifyResult:
    """Simulate ``cycles`` drive periods from the predicted equilibrium (see module docstring).

    The sideways push is a velocity of ``push_fraction * r_eq * omega / 40`` (a lateral
    oscillation of some ten micrometres for the story's pair), enough to excite both whirls.
    The state counts as bound when the run ends ``ok`` and the axial distance stays within
    ``tolerance`` (relative) of r_eq.
    """
    r_eq = state.r
    push = push_fraction * r_eq * omega / 40.0
    scene = scene_from_dict(build_scene(pair, omega, state, cycles, push), source="<predict>")
    res = simulate(scene, cycles=cycles, drift_threshold=drift_threshold)
    pos = res.positions_m[:, 0, :]
    axial_distance = np.abs(pos[:, 2])
    spp = max(1, int(round((len(res.times_s) - 1) / res.cycles))) if res.cycles else 1
    n = (len(pos) - 1) // spp
    # cycle averages remove the forced motion at the drive frequency (lateral circle, Sec. 5.2)
    avg = pos[1:1 + n * spp].reshape(n, spp, 3).mean(axis=1) if n > 0 else pos
    dt = res.period_s
    mass = pair.floator.mass_kg
    axial = oscillation(avg[:, 2], dt, mass, lateral=False)
    lateral = oscillation(avg[:, 0] + 1j * avg[:, 1], dt, mass, lateral=True)
    dist = axial_distance
    bound = res.status == "ok" and bool(np.all(np.abs(dist - r_eq) <= tolerance * r_eq))
    return VerifyResult(
        res.status, res.status_detail or "", int(res.cycles), bound, float(np.mean(dist)),
        float(np.min(dist)), float(np.max(dist)), res.invariant, float(res.invariant_drift or 0.0),
        axial, lateral, float(res.wall_s), float(res.compile_s or 0.0),
    )
