"""The result of a simulation: samples, invariants, status and quantities of interest.

Attitudes (docs/decisions/0015-store-what-the-scene-needs.md): every body's axis in the lab
(``axes``); the rotation matrix only for bodies that need one (:mod:`labkit.sim.attitude`).
"""

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
    (n, bodies, 3), ``axes`` (n, bodies, 3) each body's unit axis ``axis_body[b]`` (its dipole
    direction, see :mod:`labkit.sim.attitude`) in the lab, ``rotation_matrices`` {body index:
    (n, 3, 3) body -> lab} for the bodies that keep one (not an axisymmetric body, unless run with
    ``attitude="matrix"``), ``angular_velocities_rad_s`` (n, bodies, 3) in the lab frame.
    ``status`` is ``ok`` only when nothing went wrong."""

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
    axes: np.ndarray
    axis_body: np.ndarray
    rotation_matrices: dict[int, np.ndarray]
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

    @property
    def axis_only(self) -> list[str]:
        """Names of the bodies whose rotation about their axis was not kept (axisymmetric)."""
        return [n for b, n in enumerate(self.body_names) if b not in self.rotation_matrices]

    @property
    def rotations(self) -> np.ndarray:
        """(n, bodies, 3, 3) body -> lab, when every body kept its rotation matrix."""
        return np.stack([self.rotation(b) for b in range(len(self.body_names))], axis=1)

    def rotation(self, body: int = 0) -> np.ndarray:
        """(n, 3, 3) body -> lab rotations of ``body``; a clear error for an axisymmetric body
        whose run kept only its axis."""
        if body not in self.rotation_matrices:
            raise ValueError(
                f"body {self.body_names[body]!r} is axisymmetric: this run kept its axis (SimResult.axes), "
                "not its turn about it; simulate(..., attitude='matrix') or `labkit simulate --attitude "
                "matrix` keeps every rotation matrix")
        return self.rotation_matrices[body]

    def display_rotations(self, body: int = 0) -> np.ndarray:
        """(n, 3, 3) rotations for drawing ``body``: its own where kept, else the shortest turn
        taking ``axis_body`` to ``axes`` (an axisymmetric body looks the same at any turn)."""
        if body in self.rotation_matrices:
            return self.rotation_matrices[body]
        from labkit.sim.attitude import shortest_turns

        return shortest_turns(self.axis_body[body], self.axes[:, body])

    def dipole_directions(self, body: int = 0, moment_body: np.ndarray | None = None) -> np.ndarray:
        """Unit lab direction (n, 3) of ``moment_body`` (body frame), by default the body's axis
        (its dipole direction; body z for a body without dipole or symmetry). For a body that kept
        only its axis, ``moment_body`` must lie along that axis."""
        if moment_body is None:
            return self.axes[:, body]
        m = np.asarray(moment_body, float)
        m = m / np.linalg.norm(m)
        if body in self.rotation_matrices:
            return self.rotation_matrices[body] @ m
        along = float(m @ self.axis_body[body])
        if abs(abs(along) - 1.0) > 1e-9:
            raise ValueError(
                f"body {self.body_names[body]!r} kept only its axis {self.axis_body[body].tolist()}; "
                f"the direction {m.tolist()} is not along it (run with attitude='matrix')")
        return self.axes[:, body] * np.sign(along)

    def poses(self):
        """Yield ``(t, {name: (position, rotation)})`` per sample: the hook for streaming sinks
        (an axisymmetric body that kept only its axis gets :meth:`display_rotations`)."""
        shown = [self.display_rotations(b) for b in range(len(self.body_names))]
        for i, t in enumerate(self.times_s):
            yield (
                float(t),
                {n: (self.positions_m[i, b], shown[b][i]) for b, n in enumerate(self.body_names)},
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
            "attitude": {n: "matrix" if b in self.rotation_matrices else "axis"
                         for b, n in enumerate(self.body_names)},
            "spec": self.spec,
        }
        if series:
            out["series"] = {
                "times_s": self.times_s.tolist(),
                "positions_m": self.positions_m.tolist(),
                "axes": self.axes.tolist(),
                "axis_body": self.axis_body.tolist(),
                "rotations": {self.body_names[b]: r.tolist() for b, r in self.rotation_matrices.items()},
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
