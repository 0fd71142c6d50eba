"""What a fit returns: parameter estimates with uncertainties, goodness of fit, residuals.

Plain frozen data; :meth:`FitResult.to_json` gives the per-series object of the
``labkit fit --json`` schema ``{"params": {P: {"value", "stderr", "ci95"}}, "n",
"rms_residual", "warnings"}`` (plus a few extra keys documented in docs/reference/fitting.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True)
class ParamEstimate:
    """One parameter: value, standard error and 95 % confidence interval (SI units).

    ``fixed`` parameters were given, not fitted (stderr 0, interval of zero width).
    ``derived`` parameters are functions of the fitted ones (uncertainty by the delta method).
    ``bootstrap_ci95`` is filled when a bootstrap was asked for.
    """

    value: float
    stderr: float
    ci95: tuple[float, float]
    unit: str = ""
    fixed: bool = False
    derived: bool = False
    bootstrap_ci95: tuple[float, float] | None = None

    def covers(self, truth: float) -> bool:
        """True when ``truth`` lies inside the 95 % interval."""
        lo, hi = self.ci95
        return lo <= truth <= hi

    def to_json(self) -> dict:
        out: dict = {"value": _num(self.value), "stderr": _num(self.stderr),
                     "ci95": [_num(self.ci95[0]), _num(self.ci95[1])]}
        if self.unit:
            out["unit"] = self.unit
        if self.fixed:
            out["fixed"] = True
        if self.derived:
            out["derived"] = True
        if self.bootstrap_ci95 is not None:
            out["bootstrap_ci95"] = [_num(self.bootstrap_ci95[0]), _num(self.bootstrap_ci95[1])]
        return out


@dataclass(frozen=True)
class FitResult:
    """A finished fit of one series.

    ``x``/``y`` are the data as fitted (SI); ``residuals`` are data minus model in the fit's
    residual space, described by ``residual_space`` (e.g. ``"ln(force)"`` or ``"spin_rad_s"``).
    ``predict(x)`` evaluates the fitted model in data space (for plots and overlays).
    ``aic`` is comparable only between models fitted in the same residual space.
    """

    model: str
    params: dict[str, ParamEstimate]
    n: int
    dof: int
    rms_residual: float
    residual_space: str
    residuals: np.ndarray
    x: np.ndarray
    y: np.ndarray
    predict: Callable[[ArrayLike], np.ndarray]  # x values (a list or an array) -> the model
    r_squared: float
    reduced_chi2: float
    aic: float
    condition_number: float
    correlation: np.ndarray
    fitted_names: tuple[str, ...]
    warnings: tuple[str, ...] = ()
    x_name: str = "x"
    y_name: str = "y"
    extra: dict = field(default_factory=dict)

    def value(self, name: str) -> float:
        return self.params[name].value

    def to_json(self) -> dict:
        return {
            "params": {k: p.to_json() for k, p in self.params.items()},
            "n": self.n,
            "dof": self.dof,
            "rms_residual": _num(self.rms_residual),
            "residual_space": self.residual_space,
            "r_squared": _num(self.r_squared),
            "reduced_chi2": _num(self.reduced_chi2),
            "aic": _num(self.aic),
            "condition_number": _num(self.condition_number),
            "x": self.x_name,
            "y": self.y_name,
            "warnings": list(self.warnings),
        }


def _num(v: float) -> float | None:
    """JSON has no inf/NaN: write them as null."""
    v = float(v)
    return v if math.isfinite(v) else None
