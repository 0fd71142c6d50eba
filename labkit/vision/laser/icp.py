"""Point-to-line ICP of pattern curves, several fits at once (the engine of
:mod:`labkit.vision.laser.pattern_fit`).

Every pattern is ``z(t) = c + v tau + A e^{it} + B e^{ikt}`` (:mod:`labkit.vision.shared.curves`;
Sec. 5.2.3, Sec. 6.5 Eq. 6.38). With each point's curve parameter ``t`` fixed the model is linear
in the complex ``c, v, A, B``; a fit alternates the closest-point search (a kd-tree over sampled
curve points, then Newton steps) with a weighted linear solve. Rows of :class:`FitRows` (one per
start or candidate) advance together. Pure functions: no I/O.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from labkit.vision.laser.nearest import PointTree
from labkit.vision.shared.curves import MAX_TROCHOID_B, phasors


class Coefficients(Protocol):
    """What a row starts from: a fit's ``k``, complex ``c, a, b`` and ``drift``."""

    k: int
    c: complex
    a: complex
    b: complex
    drift: complex


@dataclass
class FitRows:
    """Several fits of the same points advanced together (one row per start or candidate): complex
    coefficients ``c, a, b, v`` and integer ``k``, each of shape (S,). Batching the rows turns
    many small array operations into a few larger ones (the fit of a 250-point trace is
    dominated by per-call overhead, not arithmetic)."""

    k: np.ndarray
    c: np.ndarray
    a: np.ndarray
    b: np.ndarray
    v: np.ndarray

    def col(self, name: str) -> np.ndarray:
        return getattr(self, name)[:, None]

    def take(self, index: list[int] | np.ndarray) -> FitRows:
        """The rows at ``index``."""
        return FitRows(self.k[index], self.c[index], self.a[index], self.b[index], self.v[index])

    @staticmethod
    def of(fits: Sequence[Coefficients]) -> FitRows:
        """One row per fit, starting where the fit ended."""
        return FitRows(np.array([f.k for f in fits]), np.array([f.c for f in fits], complex),
                     np.array([f.a for f in fits], complex), np.array([f.b for f in fits], complex),
                     np.array([f.drift for f in fits], complex))


def closest_parameters(z: np.ndarray, rows: FitRows, samples: np.ndarray) -> np.ndarray:
    """Parameter t of the closest point of each row's centred curve ``A e^{it} + B e^{ikt}`` to
    each of that row's z (S, N): nearest of ``samples`` curve points, then two Newton steps on
    ``|z(t) - p|^2``."""
    t = np.empty(z.shape)
    for i in range(len(z)):
        ts, e1, ek = _sampled_phasors(int(samples[i]), int(rows.k[i]))
        _, idx = PointTree(rows.a[i] * e1 + rows.b[i] * ek).query(z[i])
        t[i] = ts[idx]
    return newton_parameters(z, rows, t, 2)


@functools.lru_cache(maxsize=64)
def _sampled_phasors(samples: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``samples`` parameters uniform in [0, 2 pi) and their :func:`phasors` (read-only: shared
    by every fit with this k; a fit with many starts asks for the same ones per row and step)."""
    ts = np.linspace(0.0, 2 * math.pi, samples, endpoint=False)
    arrays = (ts, *phasors(ts, k))
    for a in arrays:
        a.flags.writeable = False
    return arrays


def newton_parameters(z: np.ndarray, rows: FitRows, t: np.ndarray, steps: int,
                      at_t: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Refine closest-point parameters (S, N) by Newton steps on ``|A e^{it} + B e^{ikt} - z|^2``;
    ``at_t``: the :func:`phasors` of ``t`` if already known."""
    a, b, k = rows.col("a"), rows.col("b"), rows.col("k")
    for step_index in range(steps):
        e1, ek = at_t if at_t is not None and step_index == 0 else phasors(t, k)
        a_e1, b_ek = a * e1, b * ek
        d = a_e1 + b_ek - z
        d1 = 1j * (a_e1 + k * b_ek)
        d2 = -(a_e1 + k * k * b_ek)
        g = (np.conj(d) * d1).real
        h = (np.abs(d1) ** 2 + (np.conj(d) * d2).real)
        step = np.where(h > 1e-12, g / np.maximum(h, 1e-12), 0.0)
        t = t - np.clip(step, -0.2, 0.2)
    return t


TANGENTIAL_WEIGHT = 0.2  # share of the along-curve residual kept in the solve (stabilises it)


def solve_point_to_line(z: np.ndarray, sw: np.ndarray, tau: np.ndarray, rows: FitRows,
                         at_t: tuple[np.ndarray, np.ndarray], fit_drift: bool) -> np.ndarray:
    """One linear solve per row for complex ``c, A, B (, v)`` (S, 3 or 4) with the curve parameters
    t (S, N) fixed (``at_t``: their :func:`phasors`), minimising the residual along each point's
    curve normal plus ``TANGENTIAL_WEIGHT`` times the residual along the tangent (point-to-line
    ICP: it converges in a few steps where plain point-to-point ICP slides slowly along the curve).

    The normal equations are summed in complex form. With the basis ``g_j`` (1, e^{it}, e^{ikt},
    tau), a unit direction ``d`` and ``q_j = conj(d) g_j``, the real least-squares rows are
    ``(Re q_j, -Im q_j)``, and ``Re q_j Re q_l = Re(q_j conj(q_l) + q_j q_l) / 2`` (likewise
    for the other three products). Over the normal ``d = i T`` (weight 1) and the tangent
    ``d = T`` (weight w_t) the two sums are ``(1 + w_t^2) |T|^2 g_j conj(g_l)`` and
    ``(w_t^2 - 1) conj(T)^2 g_j g_l``: two batched (S, J, N) x (S, N, J) products instead of
    2J real columns per point and direction."""
    e1, ek = at_t
    tangent = 1j * (rows.col("a") * e1 + rows.col("k") * rows.col("b") * ek)
    tangent = tangent / np.maximum(np.abs(tangent), 1e-12)
    basis = [np.ones_like(e1), e1, ek]
    if fit_drift:
        basis.append(np.broadcast_to(tau.astype(complex), e1.shape))
    g = np.stack(basis, axis=1)                                      # (S, J, N)
    w = sw * sw
    along = (1.0 + TANGENTIAL_WEIGHT ** 2) * w * (tangent.real ** 2 + tangent.imag ** 2)
    across = (TANGENTIAL_WEIGHT ** 2 - 1.0) * w * np.conj(tangent) ** 2
    g_conj_t = np.conj(g).swapaxes(1, 2)                             # (S, N, J)
    plain, turned = g * along[:, None, :], g * across[:, None, :]
    sum_conj, sum_plain = plain @ g_conj_t, turned @ g.swapaxes(1, 2)  # (S, J, J)
    z_conj, z_plain = plain @ np.conj(z[0]), turned @ z[0]           # (S, J); z: (1, N)
    j = g.shape[1]
    m = np.empty((g.shape[0], 2 * j, 2 * j))
    m[:, 0::2, 0::2] = 0.5 * (sum_conj + sum_plain).real
    m[:, 1::2, 1::2] = 0.5 * (sum_conj - sum_plain).real
    m[:, 0::2, 1::2] = 0.5 * (sum_conj - sum_plain).imag
    m[:, 1::2, 0::2] = -0.5 * (sum_conj + sum_plain).imag
    y = np.empty((g.shape[0], 2 * j))
    y[:, 0::2] = 0.5 * (z_conj + z_plain).real
    y[:, 1::2] = -0.5 * (z_conj + z_plain).imag
    try:
        x = np.linalg.solve(m, y[:, :, None])[:, :, 0]
    except np.linalg.LinAlgError:
        x = np.stack([np.linalg.lstsq(m[i], y[i], rcond=None)[0] for i in range(len(m))])
    return x[:, 0::2] + 1j * x[:, 1::2]


def icp_rows(z: np.ndarray, w: np.ndarray, tau: np.ndarray, rows: FitRows, iterations: int, fit_drift: bool,
              samples: np.ndarray, settle_px: float | None = None) -> tuple[FitRows, np.ndarray]:
    """Point-to-line ICP of every row on the same points; returns the rows and their weighted rms
    residuals (inf for a degenerate trochoid whose second term dominates: a circle traced |k|
    times). Stops early once every row has stopped moving: every sixth step when no row's ``c, A,
    B`` moved by 1e-3 px, or with ``settle_px`` after the first step in which none moved by that
    with each point's closest curve point searched afresh (a step of Newton refinements that settles
    is followed by such a search: near a trochoid's crossings Newton keeps a point on the wrong
    branch)."""
    sw = np.sqrt(w)
    trochoid = rows.k != -1
    t = None

    def centred() -> np.ndarray:
        return z[None, :] - rows.col("c") - rows.col("v") * tau[None, :]

    searched = False  # settling is judged on a step whose closest points were searched afresh
    at_t = None  # the phasors of t: they depend on t and k only, so a Newton step reuses the solve's
    for it in range(iterations):
        if it % 6 == 0 or searched:
            t = closest_parameters(centred(), rows, samples)
        else:
            assert t is not None  # set at iteration 0 (it % 6 == 0)
            t = newton_parameters(centred(), rows, t, 2, at_t)
        at_t = phasors(t, rows.col("k"))
        sol = solve_point_to_line(z[None, :], sw, tau, rows, at_t, fit_drift)
        c, a, b = sol[:, 0], sol[:, 1], sol[:, 2]
        v = sol[:, 3] if fit_drift else np.zeros_like(c)
        too_big = trochoid & (np.abs(b) > MAX_TROCHOID_B * np.abs(a))  # stay in the trochoid family
        b = np.where(too_big, b * MAX_TROCHOID_B * np.abs(a) / np.maximum(np.abs(b), 1e-300), b)
        moved = np.abs(c - rows.c) + np.abs(a - rows.a) + np.abs(b - rows.b)
        rows = FitRows(rows.k, c, a, b, v)
        if it % 6 == 5 and bool(np.all(moved < 1e-3)):
            break
        if settle_px is not None and bool(np.all(moved < settle_px)):
            if searched or it % 6 == 0:
                break
            searched = True  # Newton steps settled: search the closest points afresh, then judge
        else:
            searched = False
    if t is None or iterations < 3:
        t = closest_parameters(centred(), rows, samples)
    else:  # warm: the last parameters are close, a Newton refinement is enough
        t = newton_parameters(centred(), rows, t, 2, at_t)
    e1, ek = phasors(t, rows.col("k"))
    curve = rows.col("c") + rows.col("a") * e1 + rows.col("b") * ek
    r = np.abs(curve + rows.col("v") * tau[None, :] - z[None, :])
    rms = np.sqrt(np.sum(w * r * r, axis=1) / np.sum(w))
    degenerate = trochoid & ~(np.abs(rows.b) < 0.999 * MAX_TROCHOID_B * np.abs(rows.a))
    return rows, np.where(degenerate, math.inf, rms)
