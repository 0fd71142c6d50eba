"""The result of a simulation: samples, invariants, status and quantities of interest."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

STATUSES = ("ok", "nan", "blowup", "contact", "escape", "solver_failed", "invariant_drift", "rotation_drift")


@dataclass
class SimResult:
    """A finished run. Arrays are SI: ``times_s`` (n,), ``positions_m`` / ``velocities_m_s``
    (n, bodies, 3), ``rotations`` (n, bodies, 3, 3) body -> lab, ``angular_velocities_rad_s``
    (n, bodies, 3) in the lab frame. ``status`` is ``ok`` only when nothing went wrong."""

    scene: str
    integrator: str
    setting: dict
    status: str
    status_detail: str
    cycles: float
    period_s: float
    times_s: np.ndarray
    body_names: list[str]
    positions_m: np.ndarray
    velocities_m_s: np.ndarray
    rotations: np.ndarray
    angular_velocities_rad_s: np.ndarray
    invariant: str
    invariant_values: np.ndarray
    invariant_drift: float
    rotation_residual: float
    qoi: dict
    compile: dict
    wall_s: float
    n_force_evals: int
    event_time_s: float | None = None
    compile_s: float = 0.0
    momentum_drift: float | None = None
    angular_momentum_drift: float | None = None
    damping_change: np.ndarray | None = None  # (n,) damping's accumulated change of E - w J_z (J)
    reduced_angle_rad: np.ndarray | None = None
    reduced_rate_rad_s: np.ndarray | None = None
    spec: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def dipole_directions(self, body: int = 0, moment_body: np.ndarray | None = None) -> np.ndarray:
        """Unit dipole direction in the lab (n, 3); ``moment_body`` defaults to body z."""
        m = np.array([0.0, 0.0, 1.0]) if moment_body is None else np.asarray(moment_body, float)
        m = m / np.linalg.norm(m)
        return self.rotations[:, body] @ m

    def poses(self):
        """Yield ``(t, {name: (position, rotation)})`` per sample: the hook for streaming sinks."""
        for i, t in enumerate(self.times_s):
            yield (
                float(t),
                {n: (self.positions_m[i, b], self.rotations[i, b]) for b, n in enumerate(self.body_names)},
            )

    def to_json(self, series: bool = False) -> dict:
        """JSON-ready dict: summary always; the sampled series if ``series``."""
        out = {
            "scene": self.scene,
            "integrator": self.integrator,
            "setting": self.setting,
            "status": self.status,
            "status_detail": self.status_detail,
            "event_time_s": self.event_time_s,
            "cycles": self.cycles,
            "period_s": self.period_s,
            "duration_s": float(self.times_s[-1] - self.times_s[0]) if len(self.times_s) else 0.0,
            "invariant": self.invariant,
            "invariant_drift": _num(self.invariant_drift),
            "momentum_drift": _num(self.momentum_drift),
            "angular_momentum_drift": _num(self.angular_momentum_drift),
            "rotation_residual": _num(self.rotation_residual),
            "damping_change_J": _num(self.damping_change[-1]) if self.damping_change is not None else None,
            "qoi": _clean(self.qoi),
            "compile": _clean(self.compile),
            "wall_s": self.wall_s,
            "compile_s": self.compile_s,
            "n_force_evals": self.n_force_evals,
            "bodies": self.body_names,
            "spec": self.spec,
        }
        if series:
            out["series"] = {
                "times_s": self.times_s.tolist(),
                "positions_m": self.positions_m.tolist(),
                "rotations": self.rotations.tolist(),
                "angular_velocities_rad_s": self.angular_velocities_rad_s.tolist(),
                "invariant": self.invariant_values.tolist(),
            }
        return out

    def write_json(self, path: str | Path, series: bool = False) -> None:
        Path(path).write_text(json.dumps(self.to_json(series), indent=2) + "\n")


def _num(x: float | None) -> float | None:
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _clean(obj):
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, np.generic):
        return _clean(obj.item())
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    return obj
