"""The fits the live view redraws at every point (pure functions, no rerun).

They are the fits ``labkit fit`` makes, in the same residual space (docs/reference/fitting.md), found
by the model name a protocol's hints give (:data:`LIVE_FITS`):

* :func:`power_law_fit`: Fig. 5.25, ``F = a x^b`` fitted as a straight line in ln F against
  ln x (``labkit fit --model power-law``), with the 95 % confidence band of the fitted curve.
* :func:`eq637_fit`: Fig. 6.18, Eq. 6.37 ``-k w^2 = C (1 - w/w_c)``, ``k = v/w - 1``, solved for
  the spin, ``v = w + C (1/w_c - 1/w)``: linear in C, fitted in v (``labkit fit --model
  spin-critical`` with w_c = 3000 rad/s), with its 95 % band.
* :func:`cone_angle_fit`: Eq. 5.24, ``phi = atan(tau_C / (I w^2 - tau_S))``, fitted in phi
  (``labkit fit --model cone-angle`` without the inertia: the torques over I), with its 95 %
  band by the delta method. It takes the hints' units (x in RPM or rad/s, y in deg or rad).

A fit is called ``fit(xs, ys)`` with the figure's x and y as the hints name them; a fit whose
function has the keyword parameters ``x_unit`` and ``y_unit`` also gets the hints' units. Adding
an entry to :data:`LIVE_FITS` is all a new protocol's hints need.

The quick fit written to results.json (:mod:`labkit.protocols.quickfit`) is a different
least-squares problem; docs/reference/fitting.md says why the digits differ.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from labkit.units import RAD_S_PER_RPM, UNIT_SUFFIXES

#: smallest number of points for a fit with a spread (two parameters need three)
MIN_POINTS_POWER_LAW = 3
MIN_POINTS_EQ637 = 2
MIN_POINTS_CONE = 3

Band = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
#: the x units a live fit of a speed reads (factor to rad/s) and the y units of an angle (to rad)
SPEED_TO_RAD_S = {"rad/s": 1.0, "RPM": RAD_S_PER_RPM}
ANGLE_TO_RAD = {"rad": 1.0, "deg": UNIT_SUFFIXES["deg"][1]}


@dataclass(frozen=True)
class LiveFit:
    """A fit with its curve: ``params`` name -> (value, stderr); ``curve(x)`` -> (y, lo, hi);
    ``label`` the legend (parameters with standard errors and n)."""

    model: str
    params: dict[str, tuple[float, float]]
    n: int
    label: str
    band: Band

    def curve(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The fitted y at ``x`` and its 95 % confidence band (lower, upper)."""
        return self.band(np.asarray(x, dtype=float))


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
    coef, cov, t95 = np.asarray(fit.ln_coef), np.asarray(fit.ln_cov), _t95(fit.n - 2)

    def band(xs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        design = np.column_stack([np.ones_like(xs), np.log(xs)])
        ln_y = design @ coef
        half = t95 * np.sqrt(np.einsum("ij,jk,ik->i", design, cov, design))
        return np.exp(ln_y), np.exp(ln_y - half), np.exp(ln_y + half)

    label = (f"fit (ln F): a = {fit.a:.3g} +/- {fit.stderr_a:.1g}, b = {fit.b:.3f} +/- {fit.stderr_b:.3f}, "
             f"n = {fit.n}")
    return LiveFit("power-law", {"a": (fit.a, fit.stderr_a), "b": (fit.b, fit.stderr_b)}, fit.n, label, band)


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
    t95 = _t95(dof)

    def band(xs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        gx = 1.0 / w_c - 1.0 / xs
        y = xs + c * gx
        half = t95 * np.abs(gx) * math.sqrt(var_c)
        return y, y - half, y + half

    label = f"Eq. 6.37 fit (in v): C = {c:.4g} +/- {math.sqrt(var_c):.2g}, n = {len(w)}"
    return LiveFit("eq6.37", {"C": (c, math.sqrt(var_c))}, len(w), label, band)


def cone_angle_fit(speed: list[float], angle: list[float], *, x_unit: str = "rad/s",
                   y_unit: str = "rad") -> LiveFit | None:
    """Eq. 5.24 by least squares in the cone angle: ``tau_C/I`` and ``tau_S/I`` (s^-2) of
    :func:`labkit.fit.models.cone_angle.fit_cone_angle`, the report's ``cone-angle`` fit without
    the inertia (the angle depends on the torques over I only). None below three points, for
    units it does not know, or when the fit fails (a point at exactly zero, one speed only).
    The band: the delta method on the two fitted torques with their covariance."""
    from labkit.errors import FitError
    from labkit.fit.models.cone_angle import fit_cone_angle

    to_rad_s, to_rad = SPEED_TO_RAD_S.get(x_unit), ANGLE_TO_RAD.get(y_unit)
    if to_rad_s is None or to_rad is None:
        return None
    w = np.asarray(speed, float) * to_rad_s
    phi = np.asarray(angle, float) * to_rad
    keep = np.isfinite(w) & np.isfinite(phi) & (w > 0) & (phi != 0)
    w, phi = w[keep], phi[keep]
    if len(w) < MIN_POINTS_CONE:
        return None
    try:
        res = fit_cone_angle(w, phi)
    except FitError:
        return None
    (c, sc), (s, ss) = ((res.params[k].value, res.params[k].stderr) for k in ("tau_C_over_I", "tau_S_over_I"))
    rho = float(res.correlation[0, 1]) if np.shape(res.correlation) == (2, 2) else 0.0
    cov = np.array([[sc * sc, rho * sc * ss], [rho * sc * ss, ss * ss]])
    t95 = _t95(len(w) - 2)

    def band(xs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        denom = (xs * to_rad_s) ** 2 - s
        u = c / denom
        y = np.arctan(u)
        grad = np.column_stack([1.0 / denom, c / denom**2]) / (1.0 + u * u)[:, None]
        half = t95 * np.sqrt(np.einsum("ij,jk,ik->i", grad, cov, grad))
        return y / to_rad, (y - half) / to_rad, (y + half) / to_rad

    label = (f"Eq. 5.24 fit (in phi): tau_C/I = {c:.4g} +/- {sc:.2g}, tau_S/I = {s:.4g} +/- {ss:.2g} s^-2, "
             f"n = {len(w)}")
    return LiveFit("cone-angle", {"tau_C_over_I": (c, sc), "tau_S_over_I": (s, ss)}, len(w), label, band)


#: ``labkit fit`` model name (a protocol's ``hints.fit``) -> the live fit redrawn at every point
LIVE_FITS: dict[str, Callable[..., LiveFit | None]] = {
    "power-law": power_law_fit,
    "spin-critical": eq637_fit,
    "cone-angle": cone_angle_fit,
}


def live_fit(model: str, x: list[float], y: list[float], x_unit: str = "",
             y_unit: str = "") -> LiveFit | None:
    """The live fit ``model`` of the points (None: no such fit, or too few points). A fit that
    takes ``x_unit``/``y_unit`` gets the hints' units; the others take the numbers as they are."""
    fit = LIVE_FITS.get(model)
    if fit is None:
        return None
    wants = inspect.signature(fit).parameters
    if "x_unit" in wants and "y_unit" in wants:
        return fit(x, y, x_unit=x_unit, y_unit=y_unit)
    return fit(x, y)
