"""Spin-critical pairs of Fig. 6.18: -k omega^2 = C (1 - omega/omega_c), k = v_S/omega - 1.

Eq. 6.37 (Eq. 5.69 when omega_c is infinite). With k = v_S/omega - 1 the left side is
omega (omega - v_S), so the spin the tachometer reads at the drop is

    v_S = omega - C (1/omega - 1/omega_c) = omega + D - C/omega,   D = C/omega_c.

Residuals are in v_S (rad/s), the measured quantity. The model is linear in C (omega_c fixed)
or in (C, D) (omega_c fitted), so the t-based 95 % intervals are exact for Gaussian noise;
omega_c = C/D is a derived parameter (delta method).
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
from labkit.model.mbs import spin_for_speed

MODEL = "spin-critical"
PAPER_OMEGA_C = 3000.0  # rad/s, Eq. 6.37


def critical_spin(omega: np.ndarray, C: float, omega_c: float = PAPER_OMEGA_C) -> np.ndarray:
    """Floator spin v_S (rad/s) at the critical equilibrium for rotor speed omega (Eq. 6.37).

    ``omega_c = math.inf`` gives Eq. 5.69 (constant C). The closed form of :mod:`labkit.model`.
    """
    return spin_for_speed(omega, C, omega_c)


def fit_spin_critical(omega, spin, *, omega_c: float | str = PAPER_OMEGA_C, sigma=None,
                      x_name: str = "rotor_rad_s", y_name: str = "spin_rad_s") -> FitResult:
    """Fit C with ``omega_c`` fixed (a number, ``math.inf`` for Eq. 5.69) or ``"fit"``."""
    omega = require_finite(MODEL, x_name, omega)
    spin = require_finite(MODEL, y_name, spin)
    require_points(MODEL, len(omega), 2 if omega_c == "fit" else 1)
    require_positive(MODEL, x_name, omega, "rotor speeds of the pairs")
    require_spread(MODEL, x_name, omega)
    sigma = require_sigma(MODEL, "sigma", sigma)
    weights = None if sigma is None else 1.0 / sigma
    lhs = omega * (omega - spin)                       # -k omega^2
    c_scale = float(np.median(np.abs(lhs))) or 1.0
    fit_wc = isinstance(omega_c, str)
    if fit_wc and omega_c != "fit":
        raise FitError(f"{MODEL}: omega_c must be a number, 'inf' or 'fit', got {omega_c!r}")
    if not fit_wc and not omega_c > 0:
        raise FitError(f"{MODEL}: omega_c must be positive, got {omega_c}")

    if fit_wc:
        d_scale = c_scale / float(np.max(omega))

        def predict(t, xs):
            return xs + d_scale * t[1] - c_scale * t[0] / xs

        # linear least squares gives the exact start
        A = np.column_stack([-c_scale / omega, d_scale * np.ones_like(omega)])
        theta0 = np.linalg.lstsq(A, spin - omega, rcond=None)[0]
        params = [Param("C", lambda t: c_scale * t[0], unit="s^-2"),
                  Param("omega_c", lambda t: c_scale * t[0] / (d_scale * t[1]) if t[1] != 0 else math.inf,
                        unit="rad/s", derived=True)]
        names = ("C", "C/omega_c")
    else:
        def predict(t, xs):
            return xs - c_scale * t[0] * (1.0 / xs - 1.0 / float(omega_c))

        theta0 = [float(np.sum(lhs * (1 - omega / omega_c)) / np.sum((1 - omega / omega_c) ** 2)) / c_scale
                  if math.isfinite(omega_c) else 1.0]
        params = [Param("C", lambda t: c_scale * t[0], unit="s^-2"),
                  Param("omega_c", lambda t: float(omega_c), unit="rad/s", fixed=True)]
        names = ("C",)
    result = solve(
        model=MODEL, model_rs=lambda t: predict(t, omega), y_rs=spin, theta0=theta0, theta_names=names,
        params=params,
        x=omega, y=spin,
        predict_with=predict,
        residual_space=y_name, weights=weights, x_name=x_name, y_name=y_name,
    )
    return result if not fit_wc else _check_omega_c(result)


def _check_omega_c(result: FitResult) -> FitResult:
    from dataclasses import replace
    wc = result.params["omega_c"]
    warns = list(result.warnings)
    if not (wc.value > 0) or wc.ci95[0] <= 0 <= wc.ci95[1] or not math.isfinite(wc.value):
        warns.append("omega_c not determined: the data are consistent with no 1 - omega/omega_c term "
                     "(Eq. 5.69); fix omega_c (e.g. 3000 as in Eq. 6.37)")
    return replace(result, warnings=tuple(warns))
