"""Power law y = a x^b (the paper's Fig. 5.25 fit, y = 224e6 x^-1.9 with x in RPM, y in g).

Fitted in log space (relative errors, as a balance's noise scales with the reading and as
the paper plots it log-log): ln y = ln a' + b (ln x - ln x0), with x0 the geometric mean of
x so that ln a' and b are uncorrelated; ``a = a' x0^-b`` follows exactly.

:func:`least_squares_power_law` is the plain least-squares power law the live view
(:mod:`labkit.stream.livefit`, in ln y) and the quick fit written to results.json
(:mod:`labkit.protocols.quickfit`, in y) both call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from labkit.fit.checks import (
    require_finite,
    require_points,
    require_positive,
    require_sigma,
    require_spread,
)
from labkit.fit.engine import Param, solve
from labkit.fit.result import FitResult

MODEL = "power-law"


def power_law(x: np.ndarray, a: float, b: float) -> np.ndarray:
    """y = a x^b."""
    return a * np.power(np.asarray(x, dtype=float), b)


def fit_power_law(x, y, *, sigma=None, x_name: str = "x", y_name: str = "y",
                  model: str = MODEL, names: tuple[str, str] = ("a", "b")) -> FitResult:
    """Fit y = a x^b; ``sigma`` (absolute, in y units) weights the points relative to each other."""
    x = require_finite(model, x_name, x)
    y = require_finite(model, y_name, y)
    require_points(model, len(x), 2)
    require_positive(model, x_name, x, "a power law is fitted in log space")
    require_positive(model, y_name, y, "a power law is fitted in log space; negative or zero "
                     "forces mean a tare or sign problem")
    require_spread(model, x_name, x)
    require_spread(model, y_name, y)
    sigma = require_sigma(model, "sigma", sigma)
    lx = np.log(x)
    lx0 = float(lx.mean())
    u = lx - lx0
    ly = np.log(y)
    weights = None if sigma is None else y / sigma  # d(ln y) = dy / y
    b0 = float(np.polyfit(u, ly, 1)[0])
    theta0 = [float(ly.mean()), b0]
    na, nb = names
    params = [
        Param(na, lambda t: math.exp(t[0] - t[1] * lx0), positive=True),
        Param(nb, lambda t: float(t[1]), zero_ok=True),
    ]
    result = solve(
        model=model,
        model_rs=lambda t: t[0] + t[1] * u,
        y_rs=ly,
        theta0=theta0,
        theta_names=(f"ln {na}'", nb),
        params=params,
        x=x, y=y,
        predict_with=lambda t, xs: np.exp(t[0] + t[1] * (np.log(xs) - lx0)),
        residual_space=f"ln({y_name})",
        weights=weights,
        x_name=x_name, y_name=y_name,
    )
    return _check_exponent(result, nb, float(np.ptp(lx)))


EXPONENT_HALF_WIDTH = 0.5   # a 95 % interval wider than +-0.5 does not fix an exponent


def _check_exponent(result: FitResult, name: str, log_span: float) -> FitResult:
    from dataclasses import replace
    p = result.params[name]
    half = (p.ci95[1] - p.ci95[0]) / 2
    if half <= EXPONENT_HALF_WIDTH or any(name + " not identifiable" in w for w in result.warnings):
        return result
    return replace(result, warnings=(*result.warnings,
                   f"exponent {name} not identifiable: 95 % interval +-{half:.2g}; x spans only a factor "
                   f"{_factor(log_span)} (the paper's Fig. 5.25 spans ~3): widen the range"))


def _factor(log_span: float) -> str:
    """``exp(log_span)`` in words, also where it is beyond a float (x from 1e-311 to 1)."""
    return f"{math.exp(log_span):.3g}" if log_span < 700 else f"10^{log_span / math.log(10):.0f}"


#: the two least-squares problems :func:`least_squares_power_law` solves (docs/reference/fitting.md)
RESIDUALS = ("log", "linear")


@dataclass(frozen=True)
class PowerLawFit:
    """``y = a x^b`` with standard errors. For ``residuals="log"`` also the straight line in
    ln y: ``ln_coef`` = (ln a, b) and its covariance ``ln_cov`` (2 x 2), for a confidence band."""

    a: float
    b: float
    stderr_a: float
    stderr_b: float
    n: int
    residuals: str
    ln_coef: tuple[float, float] | None = None
    ln_cov: tuple[tuple[float, float], tuple[float, float]] | None = None


def least_squares_power_law(x, y, sigma=None, residuals: str = "log") -> PowerLawFit:
    """``y = a x^b`` by least squares over the points with x > 0 and y > 0 (at least three),
    the one power-law fit of the live view and the quick fit:

    * ``residuals="log"``: a straight line in ln y against ln x, unweighted (the live view's
      fit, the problem ``labkit fit --model power-law`` solves without sigma);
    * ``residuals="linear"``: least squares in y, weighted by ``sigma`` (absolute, in y
      units; non-positive or NaN entries take the largest sigma), started from the log-log
      line and solved around the geometric mean of x, so a and b are not strongly correlated
      (the quick fit in results.json; recorded sessions replay against it).

    ValueError below three positive points, or with log residuals for a single x or a ``sigma``."""
    if residuals not in RESIDUALS:
        raise ValueError(f"power law: residuals must be one of {', '.join(RESIDUALS)}, got {residuals!r}")
    xa, ya = np.asarray(x, float), np.asarray(y, float)
    keep = (xa > 0) & (ya > 0)
    if keep.sum() < 3:
        raise ValueError(f"power-law fit needs >= 3 positive points, got {int(keep.sum())}")
    xa, ya = xa[keep], ya[keep]
    if residuals == "log":
        if sigma is not None:
            raise ValueError("power law: sigma weights only the fit with linear residuals")
        if np.ptp(xa) == 0:
            raise ValueError(f"power-law fit needs two or more distinct x, got only x = {xa[0]:g}")
        return _log_line(xa, ya)
    return _linear(xa, ya, None if sigma is None else np.asarray(sigma, float)[keep])


def _log_line(xa: np.ndarray, ya: np.ndarray) -> PowerLawFit:
    design = np.column_stack([np.ones_like(xa), np.log(xa)])
    coef, *_ = np.linalg.lstsq(design, np.log(ya), rcond=None)
    s2 = float(np.sum((np.log(ya) - design @ coef) ** 2)) / (len(xa) - 2)
    cov = s2 * np.linalg.inv(design.T @ design)
    a = math.exp(coef[0])
    return PowerLawFit(a, float(coef[1]), a * math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1]), len(xa), "log",
                       (float(coef[0]), float(coef[1])),
                       ((float(cov[0, 0]), float(cov[0, 1])), (float(cov[1, 0]), float(cov[1, 1]))))


def _linear(xa: np.ndarray, ya: np.ndarray, sig: np.ndarray | None) -> PowerLawFit:
    from scipy.optimize import curve_fit

    if sig is not None:
        sig = np.where(sig > 0, sig, np.nan)
        sig = None if np.isnan(sig).all() else np.where(np.isnan(sig), np.nanmax(sig), sig)
    b0, log_a0 = np.polyfit(np.log(xa), np.log(ya), 1)
    x_ref = float(np.exp(np.mean(np.log(xa))))
    (c, b), cov = curve_fit(lambda xx, c, b: c * (xx / x_ref) ** b, xa, ya,
                            p0=(math.exp(log_a0) * x_ref**b0, b0), sigma=sig, maxfev=10000)
    a = c / x_ref**b
    ja = np.array([x_ref**-b, -a * math.log(x_ref)])   # a = c x_ref^-b: error propagation
    var_a = float(ja @ cov @ ja)
    return PowerLawFit(float(a), float(b), math.sqrt(max(var_a, 0.0)), math.sqrt(max(cov[1, 1], 0.0)),
                       len(xa), "linear")
