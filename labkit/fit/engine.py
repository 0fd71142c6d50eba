"""The least-squares engine every model uses: solve, covariance, intervals, warnings.

A model hands over a residual function of an internal, well-scaled, unconstrained parameter
vector ``theta`` (log-space for positive scales, dimensionless ratios for the rest) and a
list of public parameters as functions of ``theta``. The engine

* solves with :func:`scipy.optimize.least_squares` (trust-region, no bounds: models keep
  parameters physical by their parametrisation and check the margins themselves),
* takes the covariance ``s^2 (J^T J)^-1`` from an SVD of the Jacobian at the solution
  (``s^2`` = residual variance on ``n - p`` degrees of freedom),
* propagates it to the public parameters by the delta method (in log space for positive
  parameters, so their 95 % intervals are asymmetric and stay positive),
* uses Student-t quantiles on ``n - p`` degrees of freedom for the 95 % intervals,
* warns when the problem is ill-conditioned (scaled condition number, near-perfect
  correlation) or a parameter is not identifiable (relative uncertainty above 100 %), and
  raises :class:`labkit.errors.FitError` when no trustworthy answer exists.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from labkit.errors import FitError
from labkit.fit.result import FitResult, ParamEstimate

CONDITION_WARN = 1e6          # scaled Jacobian condition number above which we warn
CORRELATION_WARN = 0.995      # |correlation| between fitted parameters above which we warn
SINGULAR_RATIO = 1e-12        # singular-value ratio below which the problem is singular
OUT_OF_DOMAIN = 1e100         # residual where the model cannot be evaluated
MAX_NFEV_PER_PARAM = 150      # a well-posed problem converges in tens of evaluations


@dataclass(frozen=True)
class Param:
    """A public parameter as a function of the internal vector ``theta``.

    ``positive``: value > 0 always; uncertainty is propagated in log space.
    ``fixed``: given by the user, not fitted (reported with zero uncertainty).
    ``derived``: computed from fitted parameters (e.g. ``omega_c = C / D``).
    ``zero_ok``: a value consistent with zero is physical (no 'not identifiable' warning).
    """

    name: str
    value_of: Callable[[np.ndarray], float]
    unit: str = ""
    positive: bool = False
    fixed: bool = False
    derived: bool = False
    zero_ok: bool = False


def t95(dof: int) -> float:
    """Two-sided 95 % Student-t quantile for ``dof`` degrees of freedom."""
    return float(stats.t.ppf(0.975, dof))


def solve(
    *,
    model: str,
    model_rs: Callable[[np.ndarray], np.ndarray],
    y_rs: np.ndarray,
    theta0: Sequence[float],
    theta_names: Sequence[str],
    params: Sequence[Param],
    x: np.ndarray,
    y: np.ndarray,
    predict_with: Callable[[np.ndarray, np.ndarray], np.ndarray],
    residual_space: str,
    weights: np.ndarray | None = None,
    warnings: Sequence[str] = (),
    x_name: str = "x",
    y_name: str = "y",
    hint: str = "",
) -> FitResult:
    """Fit and package the result.

    ``y_rs`` is the data mapped to the residual space (e.g. ``ln F``) and ``model_rs(theta)``
    the model there; residuals are ``(y_rs - model_rs(theta)) * weights`` (weights = 1/sigma
    in residual space, relative: the covariance is scaled by the residual variance).
    ``predict_with(theta, x)`` evaluates the model in data space (plots and overlays).
    ``hint`` is added to the message when the solver does not converge.
    """
    y_rs = np.asarray(y_rs, dtype=float)
    w = np.ones_like(y_rs) if weights is None else np.asarray(weights, dtype=float)
    residuals = _residual_function(y_rs, model_rs, w)
    theta0 = np.asarray(theta0, dtype=float)
    n, p = len(y), len(theta0)
    if n <= p:
        raise FitError(
            f"{model}: {n} point(s) for {p} fitted parameter(s) ({', '.join(theta_names)}); "
            f"need at least {p + 1} to estimate uncertainties"
        )
    theta = _least_squares(model, residuals, theta0, theta_names, hint)
    r = residuals(theta)
    jac = _jacobian(residuals, theta)
    dof = n - p
    ssr = float(r @ r)
    s2 = ssr / dof
    cov_theta, cond, corr = _covariance(model, jac, s2, theta_names)
    warns = list(warnings)
    estimates = _estimates(model, params, theta, cov_theta, t95(dof), warns)
    warns += _conditioning_warnings(cond, corr, theta_names)

    raw_res = y_rs - model_rs(theta)
    ss_tot = float(np.sum((y_rs - y_rs.mean()) ** 2))
    ss_res = float(np.sum(raw_res**2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else float("nan")
    aic = n * math.log(max(ssr / n, 1e-300)) + 2 * p

    return FitResult(
        model=model,
        params=estimates,
        n=n,
        dof=dof,
        rms_residual=math.sqrt(ss_res / n),
        residual_space=residual_space,
        residuals=np.asarray(raw_res, dtype=float),
        x=np.asarray(x, dtype=float),
        y=np.asarray(y, dtype=float),
        predict=_bind(predict_with, theta.copy()),
        r_squared=r2,
        reduced_chi2=s2,
        aic=aic,
        condition_number=cond,
        correlation=corr,
        fitted_names=tuple(theta_names),
        warnings=tuple(warns),
        x_name=x_name,
        y_name=y_name,
        extra={"theta": theta.copy(), "cov_theta": cov_theta},
    )


def _residual_function(y_rs: np.ndarray, model_rs: Callable[[np.ndarray], np.ndarray],
                       w: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """Weighted residuals in residual space. Outside the model's domain (overflow, log of a
    negative) the residual is huge but finite, which steers the solver back; the solution
    itself is checked by :func:`_least_squares`."""

    def residuals(t: np.ndarray) -> np.ndarray:
        try:
            with np.errstate(all="ignore"):
                r = (y_rs - model_rs(t)) * w
        except (OverflowError, ZeroDivisionError, ValueError):
            return np.full(len(y_rs), OUT_OF_DOMAIN)
        return np.where(np.isfinite(r), r, OUT_OF_DOMAIN)

    return residuals


def _least_squares(model: str, residuals: Callable[[np.ndarray], np.ndarray], theta0: np.ndarray,
                   theta_names: Sequence[str], hint: str) -> np.ndarray:
    """Levenberg-Marquardt from ``theta0``; FitError saying why when there is no usable solution."""
    if np.any(np.abs(residuals(theta0)) >= OUT_OF_DOMAIN):
        raise FitError(f"{model}: the model is not finite at the starting point; check the data")
    with np.errstate(all="ignore"):
        sol = optimize.least_squares(residuals, theta0, method="lm", jac="3-point",
                                     x_scale=1.0, xtol=1e-10, ftol=1e-12, gtol=1e-12,
                                     max_nfev=MAX_NFEV_PER_PARAM * (len(theta0) + 1))
    if sol.status == 0:
        raise FitError(f"{model}: no convergence after {sol.nfev} evaluations: the parameters "
                       f"({', '.join(theta_names)}) wander along a flat valley, i.e. they are not "
                       f"identifiable from these data{'; ' + hint if hint else ''}")
    if sol.status < 0 or not np.all(np.isfinite(sol.x)):
        raise FitError(f"{model}: the solver did not converge ({sol.message})")
    if np.any(np.abs(residuals(sol.x)) >= OUT_OF_DOMAIN):
        raise FitError(f"{model}: the model is not finite at the solution; check the data range")
    return sol.x


def _estimates(model: str, params: Sequence[Param], theta: np.ndarray, cov_theta: np.ndarray, tq: float,
               warns: list[str]) -> dict[str, ParamEstimate]:
    """Every reported parameter with its uncertainty (warnings appended to ``warns``)."""
    estimates: dict[str, ParamEstimate] = {}
    for par in params:
        try:
            with np.errstate(all="ignore"):
                estimates[par.name] = _estimate(par, theta, cov_theta, tq, warns, model)
        except (OverflowError, ZeroDivisionError) as exc:
            raise FitError(f"{model}: {par.name} cannot be computed from the fit ({exc}); "
                           "it is not identifiable from these data") from None
    return estimates


def _conditioning_warnings(cond: float, corr: np.ndarray, theta_names: Sequence[str]) -> list[str]:
    """An ill-conditioned fit, or two parameters almost fully correlated, said in words."""
    if cond > CONDITION_WARN:
        return [f"ill-conditioned: scaled condition number {cond:.2g}; the parameters "
                f"{_worst_pair(corr, theta_names)} trade off against each other"]
    pair = _worst_pair(corr, theta_names, threshold=CORRELATION_WARN)
    return [f"parameters {pair} are almost fully correlated; only a combination is fixed"] if pair else []


def _bind(predict_with, theta: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    def predict(xs) -> np.ndarray:
        return predict_with(theta, np.asarray(xs, dtype=float))
    return predict


def _jacobian(fun: Callable[[np.ndarray], np.ndarray], theta: np.ndarray) -> np.ndarray:
    """Central-difference Jacobian with steps scaled to each parameter."""
    f0 = fun(theta)
    jac = np.empty((len(f0), len(theta)))
    for j in range(len(theta)):
        h = 1e-6 * max(1.0, abs(theta[j]))
        tp, tm = theta.copy(), theta.copy()
        tp[j] += h
        tm[j] -= h
        jac[:, j] = (fun(tp) - fun(tm)) / (2 * h)
    return jac


def _covariance(model: str, jac: np.ndarray, s2: float, names: Sequence[str]):
    """Covariance of theta, scaled condition number and correlation matrix."""
    norms = np.linalg.norm(jac, axis=0)
    if np.any(norms == 0):
        dead = [names[i] for i in np.flatnonzero(norms == 0)]
        raise FitError(f"{model}: the data do not depend on {', '.join(dead)}: not identifiable")
    js = jac / norms
    _, sv, vt = np.linalg.svd(js, full_matrices=False)
    if sv[-1] <= SINGULAR_RATIO * sv[0]:
        combo = vt[-1]
        parts = " ".join(f"{c:+.2f}*{n}" for c, n in zip(combo, names, strict=True) if abs(c) > 0.05)
        raise FitError(f"{model}: parameters not identifiable from these data: "
                       f"the combination {parts} is unconstrained")
    cond = float(sv[0] / sv[-1])
    cov_s = (vt.T / sv**2) @ vt
    cov = cov_s / np.outer(norms, norms) * s2
    d = np.sqrt(np.diag(cov_s))
    corr = cov_s / np.outer(d, d)
    return cov, cond, corr


def _gradient(fn: Callable[[np.ndarray], float], theta: np.ndarray) -> np.ndarray:
    g = np.empty(len(theta))
    for j in range(len(theta)):
        h = 1e-6 * max(1.0, abs(theta[j]))
        tp, tm = theta.copy(), theta.copy()
        tp[j] += h
        tm[j] -= h
        g[j] = (fn(tp) - fn(tm)) / (2 * h)
    return g


def _estimate(par: Param, theta, cov, tq, warns: list[str], model: str) -> ParamEstimate:
    value = float(par.value_of(theta))
    if par.fixed:
        return ParamEstimate(value, 0.0, (value, value), par.unit, fixed=True)
    if par.positive:
        if not value > 0:
            raise FitError(f"{model}: {par.name} = {value:.4g} should be positive")
        g = _gradient(lambda t: math.log(par.value_of(t)), theta)
        se_log = math.sqrt(max(float(g @ cov @ g), 0.0))
        half = min(tq * se_log, 700.0)  # beyond e^700 the interval is (0, inf) in practice
        est = ParamEstimate(value, value * se_log, (value * math.exp(-half), value * math.exp(half)),
                            par.unit, derived=par.derived)
        if se_log > 1.0:
            warns.append(f"{par.name} not identifiable: known only to a factor "
                         f"{math.exp(min(se_log, 700.0)):.3g} (1 sigma); widen the range of the data")
        return est
    g = _gradient(par.value_of, theta)
    se = math.sqrt(max(float(g @ cov @ g), 0.0))
    est = ParamEstimate(value, se, (value - tq * se, value + tq * se), par.unit, derived=par.derived)
    if se > abs(value) and not par.zero_ok:
        warns.append(f"{par.name} not identifiable: stderr {se:.3g} exceeds |value| {abs(value):.3g}; "
                     "widen the range of the data")
    return est


def _worst_pair(corr: np.ndarray, names: Sequence[str], threshold: float = 0.0) -> str:
    p = len(names)
    best, pair = threshold, ""
    for i in range(p):
        for j in range(i + 1, p):
            if abs(corr[i, j]) > best:
                best, pair = abs(corr[i, j]), f"{names[i]} and {names[j]} (correlation {corr[i, j]:+.4f})"
    return pair
