"""Axial bound state of a floator for any force law F(r) (paper Eq. 6.19-6.22, numerically).

``force_away(r)`` is the cycle-averaged magnetic force along the axis, positive pushing the
floator away from the rotator (PFR, repulsion) and negative pulling it in (static attraction).
``load`` is a constant external force, positive pushing the floator away: its weight when it
hangs beneath the rotator (the paper's case (3) below Eq. 6.22), minus its weight above it.

* stiffness S(r) = -dF/dr (Eq. 6.20), by central differences with a step-halving check;
* the largest distance with S > 0 and the largest load the state carries (below Eq. 6.22);
* the stable equilibrium F(r_e) + load = 0 with S(r_e) > 0 (Eq. 6.19).

Pure numerics: nothing here knows about magnets, so the paper's power-law example (Eq. 6.21)
is a known-answer check of the same code the dipole model uses.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar

Force = Callable[[float], float]


@dataclass(frozen=True)
class Derivative:
    """-dF/dr at r with its step-halving error estimate."""

    value: float
    error: float


def stiffness(force_away: Force, r: float, rel_step: float = 1e-3) -> Derivative:
    """S(r) = -dF/dr (Eq. 6.20): Richardson-extrapolated central differences at h and h/2; the
    error estimate is the difference between the extrapolated and the h/2 value."""
    def central(h: float) -> float:
        return -(force_away(r + h) - force_away(r - h)) / (2 * h)

    h = rel_step * r
    d1, d2 = central(h), central(h / 2)
    best = d2 + (d2 - d1) / 3
    return Derivative(best, abs(best - d2))


@dataclass(frozen=True)
class AxialBoundState:
    """Result of :func:`axial_bound_state` (SI). ``r_eq`` is NaN when there is no bound state,
    with ``reason`` saying why."""

    bound: bool
    r_eq: float
    r_eq_error: float
    stiffness: float
    stiffness_error: float
    r_limit: float
    max_load: float
    reason: str = ""


def stiffness_limit(force_away: Force, r_min: float, r_max: float, xtol: float) -> tuple[float, float]:
    """Distance of the largest net attraction on [r_min, r_max] (S = 0 there) and that attraction;
    the search starts where the force is defined (:func:`first_solved`)."""
    r_min = first_solved(force_away, r_min, r_max) or r_min
    res = minimize_scalar(lambda r: force_away(r), bounds=(r_min, r_max), method="bounded",
                          options={"xatol": xtol})
    return float(res.x), -float(res.fun)


def first_solved(net: Force, r_min: float, r_max: float, steps: int = 64) -> float | None:
    """``r_min``, or the nearest distance above it (on a geometric grid to ``r_max``) where ``net``
    is finite: close to contact the steady state can fail to exist (the cone opens past its limit),
    and a root search must start where the force is defined."""
    if math.isfinite(net(r_min)):
        return r_min
    for r in np.geomspace(r_min, r_max, steps)[1:]:
        if math.isfinite(net(float(r))):
            return float(r)
    return None


def axial_bound_state(force_away: Force, load: float, r_min: float, r_max: float,
                      xtol: float = 1e-9, r_limit: tuple[float, float] | None = None) -> AxialBoundState:
    """Stable equilibrium of ``force_away(r) + load = 0`` with r in [r_min, r_max] (Eq. 6.19).

    ``r_min`` is the contact distance (closer, the magnets touch). ``r_limit`` may pass a
    precomputed :func:`stiffness_limit` result. The equilibrium is solved to ``xtol`` and again
    to ``xtol / 2``; ``r_eq_error`` is the larger of the two tolerances and their difference.
    """
    r_lim, max_load = r_limit if r_limit is not None else stiffness_limit(force_away, r_min, r_max, xtol)
    nan = math.nan
    if load > max_load:
        return AxialBoundState(False, nan, nan, nan, nan, r_lim, max_load,
                               f"the load {load:.4g} N exceeds the largest net attraction {max_load:.4g} N")

    def net(r: float) -> float:
        return force_away(r) + load

    r_start = first_solved(net, r_min, r_lim)
    if r_start is None:
        return AxialBoundState(False, nan, nan, nan, nan, r_lim, max_load,
                               "no co-rotating steady state between contact and the stiffness limit")
    if net(r_start) <= 0:
        where = ("down to contact" if r_start == r_min
                 else f"down to {r_start * 1e3:.3g} mm (closer: no steady state)")
        return AxialBoundState(False, nan, nan, nan, nan, r_lim, max_load,
                               f"the attraction wins {where}: the magnets snap together")
    if r_lim <= r_start * (1 + 1e-9):
        return AxialBoundState(False, nan, nan, nan, nan, r_lim, max_load, "no stable branch outside contact")
    r1 = brentq(net, r_start, r_lim, xtol=xtol, rtol=1e-15)
    r2 = brentq(net, r_start, r_lim, xtol=xtol / 2, rtol=1e-15)
    s = stiffness(force_away, r2)
    return AxialBoundState(True, r2, max(abs(r1 - r2), xtol / 2), s.value, s.error, r_lim, max_load)
