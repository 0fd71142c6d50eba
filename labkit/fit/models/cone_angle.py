"""Cone angle against rotor speed: Eq. 5.24, and Eq. 5.68 when the floator spins.

Eq. 5.24 phi = atan(tau_C / (I omega^2 - tau_S)); with spin v_S (k = v_S/omega - 1, Eq. 5.65)
Eq. 5.68 phi = -atan(tau_C / (k I omega^2 + tau_S)). Both are one formula,

    phi = atan(tau_C / (I omega (omega - v_S) - tau_S)),

since -k omega^2 = omega (omega - v_S); v_S = 0 (no tachometer) gives Eq. 5.24 back.
Residuals are in phi (rad). The torques are fitted as dimensionless multiples of
I Omega^2 (Omega = median speed) so the solver sees numbers of order 0.1; the start comes
from the linear relation cot(phi) = (I X - tau_S) / tau_C, X = omega (omega - v_S).
"""

from __future__ import annotations

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
from labkit.model.cone import cone_angle_spin

MODEL = "cone-angle"


def cone_angle(omega, tau_C: float, tau_S: float, I: float, spin=0.0) -> np.ndarray:
    """Equilibrium cone angle phi (rad), Eq. 5.24 (spin 0) / Eq. 5.68 (spin v_S in rad/s).

    The closed form of :mod:`labkit.model` (``cone_angle_spin`` with k = v_S/omega - 1).
    """
    omega = np.asarray(omega, dtype=float)
    k = np.asarray(spin, dtype=float) / omega - 1.0
    return cone_angle_spin(tau_C, tau_S, I, omega, k)


def fit_cone_angle(omega, phi, *, inertia: float | None = None, spin=None, sigma=None,
                   tau_S: float | None = None, x_name: str = "speed_rad_s",
                   y_name: str = "cone_angle_rad") -> FitResult:
    """Fit tau_C and tau_S (or tau_S fixed) given the floator's moment of inertia ``inertia``."""
    omega = np.abs(require_finite(MODEL, x_name, omega))
    phi = require_finite(MODEL, y_name, phi)
    require_points(MODEL, len(omega), 1 if tau_S is not None else 2)
    require_positive(MODEL, x_name, omega, "speeds must be non-zero")
    require_spread(MODEL, x_name, omega)
    sigma = require_sigma(MODEL, "sigma", sigma)
    if np.any(phi == 0):
        raise FitError(f"{MODEL}: a cone angle of exactly 0 carries no torque information; "
                       "check the video analysis of those rows")
    v = np.zeros_like(omega) if spin is None else require_finite(MODEL, "spin_rad_s", spin)
    if inertia is not None and not inertia > 0:
        raise FitError(f"{MODEL}: the moment of inertia must be positive, got {inertia}")
    I = 1.0 if inertia is None else float(inertia)
    X = omega * (omega - v)
    scale = I * float(np.median(X))
    if scale <= 0:
        raise FitError(f"{MODEL}: the spin exceeds the rotor speed for most points; Eq. 5.68 needs "
                       "omega (omega - v_S) > 0")
    weights = None if sigma is None else 1.0 / sigma
    fixed_s = None if tau_S is None else tau_S / scale
    # start: cot(phi) = (I X - tau_S) / tau_C, linear in (1/tau_C, tau_S/tau_C)
    cot = 1.0 / np.tan(phi)
    if fixed_s is None:
        slope, icpt = np.polyfit(I * X / scale, cot, 1)
        c0 = 1.0 / slope if slope != 0 else 0.1
        s0 = -icpt * c0
    else:
        c0 = float(np.median((I * X / scale - fixed_s) / cot))
        s0 = fixed_s

    def unpack(t):
        return t[0], (fixed_s if fixed_s is not None else t[1])

    def predict(t, xs, vs=None):
        c, s = unpack(t)
        xs = np.asarray(xs, dtype=float)
        vv = 0.0 if vs is None else vs
        return np.arctan(c / (I * xs * (xs - vv) / scale - s))

    theta0 = [c0] if fixed_s is not None else [c0, s0]
    names = ("tau_C/(I W^2)",) if fixed_s is not None else ("tau_C/(I W^2)", "tau_S/(I W^2)")
    suffix = "" if inertia is not None else "_over_I"
    unit = "N m" if inertia is not None else "s^-2"
    params = [Param("tau_C" + suffix, lambda t: scale * unpack(t)[0], unit=unit),
              Param("tau_S" + suffix, lambda t: scale * unpack(t)[1], unit=unit, zero_ok=True,
                    fixed=fixed_s is not None)]
    if inertia is not None:
        params.append(Param("I", lambda t: I, unit="kg m^2", fixed=True))
    result = solve(
        model=MODEL, model_rs=lambda t: predict(t, omega, v), y_rs=phi, theta0=theta0,
        theta_names=names, params=params, x=omega, y=phi,
        predict_with=lambda t, xs: predict(t, xs),
        residual_space=y_name, weights=weights, x_name=x_name, y_name=y_name,
    )
    _, s_fit = unpack(result.extra["theta"])
    near = np.abs(I * X / scale - s_fit) < 0.02
    if near.any():
        from dataclasses import replace
        result = replace(result, warnings=(*result.warnings,
                         f"I omega^2 is within 2 % of tau_S at {int(near.sum())} point(s): Eq. 5.24 changes "
                         "sign there and the fitted torques are very sensitive to those points"))
    return result
