"""Error metrics of a run against a reference (docs/reference/bench-sim.md#error-metrics), as pure functions.

Errors are taken on stroboscopic samples only, at exact multiples of the drive period T
(docs/explanation/numerics-notes.md#unequal-moments-and-the-fig-57-artefact: anything else aliases). The state
is made dimensionless per component so that
one number compares tiny fast bodies and big slow ones (docs/explanation/numerics-notes.md#scaling): each
body's dipole
direction (a unit vector; the body z axis if it has no dipole), its angular velocity over the
drive's omega, position over the scene's length scale and velocity over length scale * omega.
The phase of a body's turn about its own symmetry axis is left out: it does not act on the
dynamics of a body whose dipole is on that axis, and its round-off (1e-9 after 1e5 steps in the
simulator's kernel) would otherwise hide every error below it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from labkit.sim.result import SimResult


@dataclass
class StateErrors:
    """DiffEqDevTools-style errors over the common stroboscopic samples."""

    final: float
    linf: float
    l2: float
    samples: int


def stroboscopic_indices(times_s: np.ndarray, period_s: float, tol: float = 1e-9) -> np.ndarray:
    """Indices of samples lying on exact multiples of the period (to ``tol`` of a period)."""
    k = np.asarray(times_s) / period_s
    return np.flatnonzero(np.abs(k - np.round(k)) <= tol)


def dipole_axes(result: SimResult, moments: list | None = None) -> np.ndarray:
    """(n, bodies, 3) unit dipole direction of every body in the lab (body z where no dipole)."""
    nb = result.axes.shape[1]
    out = np.empty(result.axes.shape)
    for b in range(nb):
        m = None if moments is None else np.asarray(moments[b], dtype=float)
        out[:, b] = result.dipole_directions(b, m if m is not None and np.linalg.norm(m) > 0 else None)
    return out


def normalised_state(
    result: SimResult, length_scale: float, omega: float, moments: list | None = None
) -> np.ndarray:
    """(n, features) dimensionless state: dipole axes, omega / w, x / l, v / (l w)."""
    n = len(result.times_s)
    parts = [
        dipole_axes(result, moments).reshape(n, -1),
        result.angular_velocities_rad_s.reshape(n, -1) / omega,
        result.positions_m.reshape(n, -1) / length_scale,
        result.velocities_m_s.reshape(n, -1) / (length_scale * omega),
    ]
    return np.concatenate(parts, axis=1)


def state_errors(
    run: SimResult, ref: SimResult, length_scale: float, omega: float, moments: list | None = None
) -> StateErrors:
    """Max-norm state error at the stroboscopic times both runs share (final, l-inf, l2)."""
    ia = stroboscopic_indices(run.times_s, run.period_s)
    ib = stroboscopic_indices(ref.times_s, ref.period_s)
    ka = np.round(run.times_s[ia] / run.period_s).astype(int)
    kb = np.round(ref.times_s[ib] / ref.period_s).astype(int)
    common, ja, jb = np.intersect1d(ka, kb, return_indices=True)
    if len(common) == 0:
        return StateErrors(math.nan, math.nan, math.nan, 0)
    a = normalised_state(run, length_scale, omega, moments)[ia[ja]]
    b = normalised_state(ref, length_scale, omega, moments)[ib[jb]]
    d = np.max(np.abs(a - b), axis=1)
    if not np.all(np.isfinite(d)):
        return StateErrors(math.nan, math.nan, math.nan, len(common))
    return StateErrors(float(d[-1]), float(d.max()), float(np.sqrt(np.mean(d**2))), len(common))


def cone_angle_mean(result: SimResult, body: int = 0) -> float:
    """Mean zenith angle (rad) of a body's dipole over the stroboscopic samples."""
    idx = stroboscopic_indices(result.times_s, result.period_s)
    u = result.dipole_directions(body)[idx]
    return float(np.mean(np.arccos(np.clip(u[:, 2], -1.0, 1.0))))


def mean_force(result: SimResult, body: int = 0) -> np.ndarray | None:
    """Cycle-averaged magnetic force (N) on a body, when the run recorded it."""
    name = result.body_names[body]
    f = result.qoi.get("bodies", {}).get(name, {}).get("mean_force_N")
    return None if f is None else np.asarray(f, dtype=float)


def qoi_errors(run: SimResult, ref: SimResult) -> dict:
    """Absolute cone-angle error (rad) and relative cycle-averaged force error (NaN if absent)."""
    out = {"cone_angle": math.nan, "mean_force": math.nan}
    try:
        out["cone_angle"] = abs(cone_angle_mean(run) - cone_angle_mean(ref))
    except (ValueError, IndexError):
        pass
    fa, fb = mean_force(run), mean_force(ref)
    if fa is not None and fb is not None and np.linalg.norm(fb) > 0:
        out["mean_force"] = float(np.linalg.norm(fa - fb) / np.linalg.norm(fb))
    return out


def drift_growth(values: np.ndarray, split: float = 0.1) -> float:
    """max |dK| over the whole run over max |dK| over its first ``split`` fraction.

    Bounded (non-secular) error gives ~1; linear drift gives ~1/split
    (docs/explanation/numerics-notes.md#targets, T1: <= 3).
    """
    v = np.asarray(values, dtype=float)
    if len(v) < 10 or not np.all(np.isfinite(v)):
        return math.nan
    d = np.abs(v - v[0])
    early = d[: max(2, int(len(d) * split))].max()
    if early == 0:
        return 1.0 if d.max() == 0 else math.inf
    return float(d.max() / early)


def observed_order(steps: list[float], errors: list[float], lo: float = 1e-13, hi: float = 1e-2) -> float:
    """Observed order from a step sweep: median of the pairwise slopes ``log(e_i/e_j)/log(N_j/N_i)``
    of consecutive points whose errors lie in the asymptotic window [lo, hi]
    (docs/explanation/numerics-notes.md#error-metrics)."""
    pts = sorted((n, e) for n, e in zip(steps, errors, strict=True) if math.isfinite(e) and lo <= e <= hi)
    slopes = [
        math.log(e0 / e1) / math.log(n1 / n0)
        for (n0, e0), (n1, e1) in zip(pts, pts[1:], strict=False)
        if n1 > n0 and e1 > 0
    ]
    return float(np.median(slopes)) if slopes else math.nan


def pareto_front(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """(cost, error) points not beaten by a cheaper point with a smaller error, by rising cost."""
    front: list[tuple[float, float]] = []
    for cost, err in sorted(p for p in points if math.isfinite(p[0]) and math.isfinite(p[1]) and p[1] > 0):
        if not front or err < front[-1][1]:
            front.append((cost, err))
    return front


def cost_to_reach(points: list[tuple[float, float]], target: float) -> float | None:
    """Cost to reach error ``target``: log-log interpolation on the Pareto front (CyRK practice).

    None if no point reaches it; the cheapest point's cost if even that one is already below it.
    """
    front = pareto_front(points)
    for i, (cost, err) in enumerate(front):
        if err <= target:
            if i == 0:
                return cost
            c0, e0 = front[i - 1]
            w = math.log(target / e0) / math.log(err / e0)
            return math.exp(math.log(c0) + w * (math.log(cost) - math.log(c0)))
    return None
