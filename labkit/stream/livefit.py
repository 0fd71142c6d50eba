"""The fits the live view redraws at every point (pure functions, no rerun).

They are the fits ``labkit fit`` makes, in the same residual space (docs/reference/fitting.md), found
by the model name a protocol's hints give (:data:`LIVE_FITS`):

* :func:`power_law_fit`: Fig. 5.25, ``F = a x^b`` fitted as a straight line in ln F against
  ln x (``labkit fit --model power-law``), with the 95 % confidence band of the fitted curve.
* :func:`eq637_fit`: Fig. 6.18, Eq. 6.37 ``-k w^2 = C (1 - w/w_c)``, ``k = v/w - 1``, solved for
  the spin, ``v = w + C (1/w_c - 1/w)``: linear in C, fitted in v (``labkit fit --model
  spin-critical`` with w_c = 3000 rad/s), with its 95 % band.

The quick fit written to results.json (:mod:`labkit.protocols.quickfit`) is a different
least-squares problem; docs/reference/fitting.md says why the digits differ.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: smallest number of points for a fit with a spread (two parameters need three)
MIN_POINTS_POWER_LAW = 3
MIN_POINTS_EQ637 = 2


@dataclass(frozen=True)
class LiveFit:
    """A fit with its curve: ``params`` name -> (value, stderr); ``curve(x)`` -> (y, lo, hi)."""

    model: str
    params: dict[str, tuple[float, float]]
    n: int
    _coef: tuple[float, ...]
    _cov: tuple[tuple[float, ...], ...]
    _t95: float

    def curve(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The fitted y at ``x`` and its 95 % confidence band (lower, upper)."""
        x = np.asarray(x, dtype=float)
        cov = np.asarray(self._cov)
        if self.model == "power-law":
            design = np.column_stack([np.ones_like(x), np.log(x)])
            ln_y = design @ np.asarray(self._coef)
            half = self._t95 * np.sqrt(np.einsum("ij,jk,ik->i", design, cov, design))
            return np.exp(ln_y), np.exp(ln_y - half), np.exp(ln_y + half)
        w_c = self._coef[1]
        g = 1.0 / w_c - 1.0 / x
        y = x + self._coef[0] * g
        half = self._t95 * np.abs(g) * math.sqrt(cov[0, 0])
        return y, y - half, y + half


def _t95(dof: int) -> float:
    from scipy.stats import t

    return float(t.ppf(0.975, dof))


def power_law_fit(x: list[float], y: list[float]) -> LiveFit | None:
    """``y = a x^b`` by least squares in ln y (None below three positive points or for a
    single x): :func:`labkit.fit.models.power_law.least_squares_power_law`, the quick fit's too."""
    from labkit.fit.models.power_law import least_squares_power_law

    try:
        fit = least_squares_power_law(x, y, residuals="log")
    except ValueError:
        return None
    assert fit.ln_coef is not None and fit.ln_cov is not None
    params = {"a": (fit.a, fit.stderr_a), "b": (fit.b, fit.stderr_b)}
    return LiveFit("power-law", params, fit.n, fit.ln_coef, fit.ln_cov, _t95(fit.n - 2))


def eq637_fit(rotor_rad_s: list[float], spin_rad_s: list[float], w_c: float = 3000.0) -> LiveFit | None:
    """C of Eq. 6.37 by least squares in the spin v (None below two pairs)."""
    w, v = np.asarray(rotor_rad_s, float), np.asarray(spin_rad_s, float)
    keep = w > 0
    w, v = w[keep], v[keep]
    if len(w) < MIN_POINTS_EQ637:
        return None
    g = 1.0 / w_c - 1.0 / w
    c = float(np.sum(g * (v - w)) / np.sum(g * g))
    dof = len(w) - 1
    var_c = float(np.sum((v - w - c * g) ** 2)) / dof / float(np.sum(g * g))
    return LiveFit("eq6.37", {"C": (c, math.sqrt(var_c))}, len(w), (c, float(w_c)),
                   ((var_c,),), _t95(dof))


#: ``labkit fit`` model name (a protocol's ``hints.fit``) -> the live fit redrawn at every point
LIVE_FITS: dict[str, Callable[[list[float], list[float]], LiveFit | None]] = {
    "power-law": power_law_fit,
    "spin-critical": eq637_fit,
}
