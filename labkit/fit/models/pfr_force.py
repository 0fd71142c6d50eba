"""PFR force against rotor speed, F = K / (I omega^2 - tau_S) (Eq. 5.81 with Eq. 5.24).

Eq. 5.81 gives F_z = M^2 a / ((I omega^2 - tau_S) r^(4+b)); at a fixed distance the numerator
is one constant K. Only K/I and tau_S/I are identifiable from F(omega): with the floator's
moment of inertia I given, K and tau_S are reported; without it, ``K_over_I`` and
``tau_S_over_I``.

Internally F = A / (omega^2 - w0sq) with w0sq = W (1 - e^u), W = the smallest omega^2 of the
data: the pole stays below the data for every u, so the solver needs no bound; a fit whose
margin e^u collapses has run into that bound and is refused. Residuals are in ln F.
"""

from __future__ import annotations

import math

import numpy as np

from labkit.errors import FitError
from labkit.fit.checks import (
    require_finite,
    require_points,
    require_positive,
    require_sigma,
    require_spread,
)
from labkit.fit.engine import Param, solve
from labkit.fit.result import FitResult

MODEL = "pfr-force"
MARGIN_ERROR = 1e-3   # (I w_min^2 - tau_S) / (I w_min^2) below this: the fit hit the pole
MARGIN_WARN = 0.05


def pfr_force(omega: np.ndarray, K: float, I: float, tau_S: float) -> np.ndarray:
    """F = K / (I omega^2 - tau_S) (Eq. 5.81 family), SI units."""
    omega = np.asarray(omega, dtype=float)
    return K / (I * omega**2 - tau_S)


def fit_pfr_force(omega, force, *, sigma=None, inertia: float | None = None,
                  tau_S: float | None = None, x_name: str = "speed_rad_s",
                  y_name: str = "force_n") -> FitResult:
    """Fit F(omega) with K and tau_S free (or ``tau_S`` fixed). ``inertia`` in kg m^2."""
    omega = np.abs(require_finite(MODEL, x_name, omega))
    force = require_finite(MODEL, y_name, force)
    require_points(MODEL, len(omega), 1 if tau_S is not None else 2)
    require_positive(MODEL, x_name, omega, "speeds must be non-zero")
    require_positive(MODEL, y_name, force, "the PFR force is repulsive and fitted in log space")
    require_spread(MODEL, x_name, omega)
    require_spread(MODEL, y_name, force)
    sigma = require_sigma(MODEL, "sigma", sigma)
    if inertia is not None and not inertia > 0:
        raise FitError(f"{MODEL}: the moment of inertia must be positive, got {inertia}")
    I = 1.0 if inertia is None else float(inertia)
    w2 = omega**2
    W = float(w2.min())
    lf = np.log(force)
    weights = None if sigma is None else force / sigma
    fixed_w0sq = None if tau_S is None else tau_S / I
    if fixed_w0sq is not None and fixed_w0sq >= W:
        raise FitError(f"{MODEL}: fixed tau_S = {tau_S:.4g} N m is not below I*omega_min^2 = {I * W:.4g}")

    def w0sq(t):
        return fixed_w0sq if fixed_w0sq is not None else W * (1.0 - math.exp(t[1]))

    def ln_model(t):
        return t[0] - np.log(w2 - w0sq(t))

    with np.errstate(divide="ignore"):
        theta0 = [float(np.mean(lf + np.log(w2)))]
    names = ["ln(K/I)"]
    if fixed_w0sq is None:
        theta0.append(0.0)
        names.append("ln margin")
    suffix = "" if inertia is not None else "_over_I"
    params = [
        Param("K" + suffix, lambda t: I * math.exp(t[0]), positive=True,
              unit="N^2 m" if inertia is not None else "N s^-2"),
        Param("tau_S" + suffix, lambda t: I * w0sq(t), unit="N m" if inertia is not None else "s^-2",
              zero_ok=True, fixed=fixed_w0sq is not None),
    ]
    if inertia is not None:
        params.append(Param("I", lambda t: I, unit="kg m^2", fixed=True))
    result = solve(
        model=MODEL, model_rs=ln_model, y_rs=lf, theta0=theta0, theta_names=names, params=params,
        x=omega, y=force,
        predict_with=lambda t, xs: np.exp(t[0]) / (np.asarray(xs) ** 2 - w0sq(t)),
        residual_space=f"ln({y_name})", weights=weights, x_name=x_name, y_name=y_name,
    )
    if fixed_w0sq is None:
        margin = 1.0 - w0sq(result.extra["theta"]) / W
        if margin < MARGIN_ERROR:
            raise FitError(
                f"{MODEL}: I*omega^2 - tau_S runs to zero at the lowest speed (margin {margin:.1e}): "
                "tau_S sits at its bound, the pole of Eq. 5.81 on the data; the speeds near "
                f"{math.sqrt(W):.4g} rad/s cannot be described, drop them or fix tau_S (--fix tau_S=...)"
            )
        if margin < MARGIN_WARN:
            warns = (*result.warnings,
                     f"I*omega^2 - tau_S is only {100 * margin:.2g} % of I*omega^2 at the lowest speed: "
                     "the fit is dominated by points near the pole and sensitive to speed calibration")
            result = _with_warnings(result, warns)
    return result


def _with_warnings(result: FitResult, warns) -> FitResult:
    from dataclasses import replace
    return replace(result, warnings=tuple(warns))
