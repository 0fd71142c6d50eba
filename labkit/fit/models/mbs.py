"""Magnetic bound state: force profile Eq. 5.85 and equilibrium distance vs speed Eq. 6.13.

Eq. 5.85  F_z(r) = a r^-b - c r^-d: PFR repulsion (a, b) against the static attraction (c, d),
all positive; the paper finds b = 7.5 +- 0.4, d = 3.8 +- 0.4. A free four-parameter fit is
ill-conditioned over the short ranges a bound state allows (the two power laws trade off), so
``fit_mbs_force`` accepts fixed exponents and warns; ``fit_mbs_parts`` fits the repulsive and
attractive parts separately when they were measured or simulated separately (e.g. rotator
tilt gamma = 0 gives the repulsion alone, a static dipole the attraction alone).

Eq. 6.13  r = (a / (c omega^2))^(1/(b - d)): a power law r = A omega^p with p = -2/(b - d);
only A and b - d are identifiable from r(omega).
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
from labkit.fit.models.power_law import fit_power_law
from labkit.fit.result import FitResult
from labkit.model.mbs import equilibrium_distance, mbs_force

__all__ = ["equilibrium_distance", "fit_mbs_distance", "fit_mbs_force", "fit_mbs_parts", "mbs_force"]

FORCE_MODEL = "mbs-force"
DISTANCE_MODEL = "mbs-distance"
PAPER_B, PAPER_D = 7.5, 3.8


def fit_mbs_force(r, force, *, sigma=None, fixed: dict[str, float] | None = None,
                  x_name: str = "distance_m", y_name: str = "force_n") -> FitResult:
    """Fit Eq. 5.85 to a total force profile; ``fixed`` may hold any of a, b, c, d."""
    fixed = dict(fixed or {})
    unknown = set(fixed) - {"a", "b", "c", "d"}
    if unknown:
        raise FitError(f"{FORCE_MODEL}: unknown parameter(s) to fix: {', '.join(sorted(unknown))} "
                       "(Eq. 5.85 has a, b, c, d)")
    r = require_finite(FORCE_MODEL, x_name, r)
    force = require_finite(FORCE_MODEL, y_name, force)
    require_points(FORCE_MODEL, len(r), 4 - len(fixed))
    require_positive(FORCE_MODEL, x_name, r, "distances between magnet centres")
    require_spread(FORCE_MODEL, x_name, r)
    require_spread(FORCE_MODEL, y_name, force)
    sigma = require_sigma(FORCE_MODEL, "sigma", sigma)
    r0 = float(np.exp(np.mean(np.log(r))))
    u = r / r0
    f_scale = float(np.max(np.abs(force)))
    b_start, d_start = fixed.get("b", PAPER_B), fixed.get("d", PAPER_D)
    # linear start for the amplitudes given exponents
    A = np.column_stack([u**-b_start, -(u**-d_start)])
    amp = np.abs(np.linalg.lstsq(A, force / f_scale, rcond=None)[0]) + 1e-3
    free = [k for k in ("a", "b", "c", "d") if k not in fixed]
    start = {"a": math.log(amp[0]), "b": b_start, "c": math.log(amp[1]), "d": d_start}
    idx = {k: i for i, k in enumerate(free)}

    def values(t):
        a_s = math.exp(t[idx["a"]]) if "a" in idx else fixed["a"] * r0 ** -fixed.get("b", b_start) / f_scale
        b = t[idx["b"]] if "b" in idx else fixed["b"]
        c_s = math.exp(t[idx["c"]]) if "c" in idx else fixed["c"] * r0 ** -fixed.get("d", d_start) / f_scale
        d = t[idx["d"]] if "d" in idx else fixed["d"]
        return a_s, b, c_s, d

    def model_scaled(t, uu):
        a_s, b, c_s, d = values(t)
        return a_s * uu**-b - c_s * uu**-d

    def public(t):
        a_s, b, c_s, d = values(t)
        return {"a": a_s * f_scale * r0**b, "b": b, "c": c_s * f_scale * r0**d, "d": d}

    params = [Param(k, (lambda t, k=k: public(t)[k]), positive=k in ("a", "c"), fixed=k in fixed,
                    unit={"a": "N m^b", "b": "", "c": "N m^d", "d": ""}[k]) for k in ("a", "b", "c", "d")]
    params.append(Param("r_eq", lambda t: _r_eq(public(t)), unit="m", derived=True))
    weights = None if sigma is None else f_scale / sigma
    result = solve(
        model=FORCE_MODEL, model_rs=lambda t: model_scaled(t, u), y_rs=force / f_scale,
        theta0=[start[k] for k in free], theta_names=tuple(free), params=params, x=r, y=force,
        predict_with=lambda t, xs: f_scale * model_scaled(t, np.asarray(xs) / r0),
        residual_space=f"{y_name}/{f_scale:.3g}", weights=weights, x_name=x_name, y_name=y_name,
        hint="fix an exponent (--fix d=3.8) or fit the repulsive and attractive parts separately "
             "(columns repulsive_n, attractive_n)",
    )
    return _rescale_residuals(result, f_scale)


def _r_eq(p: dict) -> float:
    if p["b"] == p["d"]:
        return math.nan
    return (p["a"] / p["c"]) ** (1.0 / (p["b"] - p["d"]))


def _rescale_residuals(result: FitResult, f_scale: float) -> FitResult:
    from dataclasses import replace
    return replace(result, residuals=result.residuals * f_scale, rms_residual=result.rms_residual * f_scale,
                   residual_space=result.y_name)


def fit_mbs_parts(r, repulsive, attractive, *, x_name: str = "distance_m") -> dict[str, FitResult]:
    """Fit the two terms of Eq. 5.85 separately: repulsive a r^-b and attractive c r^-d.

    ``attractive`` may be given with either sign (its magnitude is fitted). Returns series
    ``repulsive`` (params a, b) and ``attractive`` (params c, d), exponents as positive powers.
    """
    rep = fit_power_law(r, repulsive, x_name=x_name, y_name="repulsive_n", model=FORCE_MODEL,
                        names=("a", "minus_b"))
    att = fit_power_law(r, np.abs(np.asarray(attractive, dtype=float)), x_name=x_name,
                        y_name="attractive_n", model=FORCE_MODEL, names=("c", "minus_d"))
    return {"repulsive": _negate_exponent(rep, "minus_b", "b"),
            "attractive": _negate_exponent(att, "minus_d", "d")}


def _negate_exponent(result: FitResult, old: str, new: str) -> FitResult:
    from dataclasses import replace

    from labkit.fit.result import ParamEstimate
    params = {}
    for k, p in result.params.items():
        if k == old:
            params[new] = ParamEstimate(-p.value, p.stderr, (-p.ci95[1], -p.ci95[0]))
        else:
            params[k] = p
    return replace(result, params=params)


def fit_mbs_distance(omega, r, *, sigma=None, x_name: str = "speed_rad_s",
                     y_name: str = "distance_m") -> FitResult:
    """Fit Eq. 6.13, r = A omega^p, and report A, p and b - d = -2/p."""
    omega = np.abs(require_finite(DISTANCE_MODEL, x_name, omega))
    res = fit_power_law(omega, r, sigma=sigma, x_name=x_name, y_name=y_name, model=DISTANCE_MODEL,
                        names=("A", "p"))
    theta, cov = res.extra["theta"], res.extra["cov_theta"]
    p = res.params["p"]
    from dataclasses import replace

    from labkit.fit.engine import t95
    from labkit.fit.result import ParamEstimate
    if p.value == 0:
        raise FitError(f"{DISTANCE_MODEL}: the distance does not change with speed (p = 0); b - d undefined")
    bmd = -2.0 / p.value
    se = 2.0 * p.stderr / p.value**2
    tq = t95(res.dof)
    params = dict(res.params)
    params["b_minus_d"] = ParamEstimate(bmd, se, (bmd - tq * se, bmd + tq * se), derived=True)
    warns = list(res.warnings)
    if p.ci95[0] <= 0 <= p.ci95[1]:
        warns.append("b - d not identifiable: the exponent p is consistent with 0")
    del theta, cov
    return replace(res, params=params, warnings=tuple(warns))
