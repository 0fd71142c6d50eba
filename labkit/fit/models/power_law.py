"""Power law y = a x^b (the paper's Fig. 5.25 fit, y = 224e6 x^-1.9 with x in RPM, y in g).

Fitted in log space (relative errors, as a balance's noise scales with the reading and as
the paper plots it log-log): ln y = ln a' + b (ln x - ln x0), with x0 the geometric mean of
x so that ln a' and b are uncorrelated; ``a = a' x0^-b`` follows exactly.
"""

from __future__ import annotations

import math

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
                   f"{math.exp(log_span):.3g} (the paper's Fig. 5.25 spans ~3): widen the range"))
