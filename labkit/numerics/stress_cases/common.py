"""Shared parts of the stress cases: the verdict, scene builders, run helpers."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from labkit.numerics import metrics
from labkit.sim import scene_from_dict, simulate
from labkit.sim.result import SimResult

# S1 (paper Sec. 5.1, docs/explanation/numerics-notes.md#exact-conical-motion)
I_S1, OMEGA_S1, TAU_C_S1, TAU_S_S1 = 1e-7, 80 * math.pi, 1e-3, 4.633e-3


@dataclass
class Verdict:
    """A stress case's outcome: ``met`` is True/False; ``measured`` holds the numbers behind it."""

    id: str
    case: str
    criterion: str
    met: bool
    measured: dict = field(default_factory=dict)
    cycles: float = 0.0
    wall_s: float = 0.0
    detail: str = ""
    name: str = ""  # descriptive name (labkit.numerics.stress.NAMES); ``id`` is its S-number alias

    def __post_init__(self) -> None:
        self.met = bool(self.met)

    def to_json(self) -> dict:
        return {
            "id": self.id,
            "name": self.name,
            "case": self.case,
            "criterion": self.criterion,
            "met": self.met,
            "measured": {k: _clean(v) for k, v in self.measured.items()},
            "cycles": self.cycles,
            "wall_s": self.wall_s,
            "detail": self.detail,
        }


def _clean(v):
    if isinstance(v, float | np.floating):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, np.bool_):
        return bool(v)
    return v


# --------------------------------------------------------------------------- scenes


def conical_dict(
    inertia: float | list, omega: float, tau_c: float, tau_s: float, name: str, damping_rot: float = 0.0
) -> dict:
    """A one-body scene in a uniform rotating field on its conical equilibrium (Eq. 5.24/5.12)."""
    body = {
        "name": "floator",
        "mass_g": 6.68,
        "inertia_kg_m2": inertia,
        "moment_Am2": 1.0,
        "initial": {"equilibrium": "conical"},
    }
    if damping_rot:
        body["damping_rot_N_m_s"] = damping_rot
    return {
        "scene": {"name": name, "cycles": 10},
        "field": {"kind": "rotating", "omega_rad_s": omega, "tau_c_Nm": tau_c, "tau_s_Nm": tau_s},
        "body": [body],
    }


def conical_scene(inertia: float, omega: float, tau_c: float, tau_s: float, name: str, **kw):
    return scene_from_dict(conical_dict(inertia, omega, tau_c, tau_s, name, **kw), source=f"<{name}>")


def s1_like(inertia: float, omega: float, tau_s: float | None = None, name: str = "s1"):
    """S1's nondimensional torques (tau / (I omega^2)) at another inertia and speed."""
    scale = inertia * omega**2 / (I_S1 * OMEGA_S1**2)
    tau_s = TAU_S_S1 * scale if tau_s is None else tau_s
    return conical_scene(inertia, omega, TAU_C_S1 * scale, tau_s, name)


def fig5_13_dict(position_mm: float, velocity_m_s: float, escape_mm: float | None = None) -> dict:
    """Fig. 5.13's tilted rotating dipole with an *unpinned* floator on its axis (S8, S9)."""
    scene = {"name": "fig5_13_free", "cycles": 10}
    if escape_mm:
        scene["escape_radius_mm"] = escape_mm
    return {
        "scene": scene,
        "rotator": [
            {
                "name": "rotator",
                "moment_Am2": 0.25393,
                "omega_rad_s": 60 * math.pi,
                "tilt_rad": 0.07983,
                "radius_mm": 5.0,
            }
        ],
        "body": [
            {
                "name": "floator",
                "mass_g": 6.68,
                "inertia_kg_m2": 0.999e-7,
                "moment_Am2": 0.8,
                "shape": {"kind": "cylinder", "radius_mm": 5.4711, "height_mm": 9.4763},
                "initial": {
                    "position_mm": [0.0, 0.0, position_mm],
                    "velocity_m_s": [0.0, 0.0, velocity_m_s],
                    "equilibrium": "conical",
                },
            }
        ],
    }


def simulate_case(scene, cycles: float, **kw) -> SimResult:
    """:func:`labkit.sim.simulate` with the drift and rotation alarms off (a stress case
    measures the drift itself)."""
    kw.setdefault("drift_threshold", math.inf)
    kw.setdefault("rotation_threshold", math.inf)
    return simulate(scene, cycles, **kw)


def final_phase_error(res: SimResult) -> float:
    """|psi(t_end) - psi_exact(t_end)|: the dipole's azimuth at the last multiple of T against
    its start (Eq. 5.7: on the cone it is back there at every t = kT); the metric of
    docs/explanation/numerics-notes.md#exact-conical-motion."""
    idx = metrics.stroboscopic_indices(res.times_s, res.period_s)
    u = res.dipole_directions()[idx]
    az = np.unwrap(np.arctan2(u[:, 1], u[:, 0]))
    return float(abs(az[-1] - az[0]))


def stroboscopic_drift(res: SimResult) -> float:
    """max |u(kT) - u(0)|: the orientation (psi) error of a relative equilibrium (Eq. 5.7)."""
    idx = metrics.stroboscopic_indices(res.times_s, res.period_s)
    u = res.dipole_directions()[idx]
    return float(np.max(np.linalg.norm(u - u[0], axis=1)))


# --------------------------------------------------------------------------- cases

LEVELS = ("smoke", "quick", "full")


def horizon(level: str, quick: int, full: int) -> int:
    """Cycles for a level: ``full``, ``quick``, or ``smoke`` (a twentieth of quick, >= 2: for tests)."""
    if level not in LEVELS:
        raise ValueError(f"unknown level {level!r} (choose from {', '.join(LEVELS)})")
    return {"full": full, "quick": quick, "smoke": max(2, quick // 20)}[level]
