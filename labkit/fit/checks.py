"""Checks run on the data before any fit: each failure is a FitError that says what to change."""

from __future__ import annotations

import numpy as np

from labkit.errors import FitError


def _rows(mask: np.ndarray, limit: int = 5) -> str:
    idx = np.flatnonzero(mask)[:limit] + 1
    more = "..." if mask.sum() > limit else ""
    return ", ".join(str(i) for i in idx) + more


def require_finite(model: str, name: str, values: np.ndarray) -> np.ndarray:
    """Reject NaN or infinite values, naming the (1-based) data rows."""
    values = np.asarray(values, dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        raise FitError(f"{model}: column {name!r} has {int(bad.sum())} missing or non-finite value(s) "
                       f"(data row {_rows(bad)}); remove or repair those rows")
    return values


def require_positive(model: str, name: str, values: np.ndarray, why: str) -> None:
    """Reject zero or negative values where the model needs them positive (log-space fits)."""
    bad = values <= 0
    if bad.any():
        first = values[bad][0]
        raise FitError(f"{model}: column {name!r} must be positive ({why}); data row {_rows(bad)} "
                       f"has {first:.4g}")


def require_spread(model: str, name: str, values: np.ndarray) -> None:
    """Reject a column whose values are all equal: nothing to fit against."""
    if np.ptp(values) == 0:
        raise FitError(f"{model}: all {len(values)} values of {name!r} are equal ({values[0]:.6g}); "
                       "a fit needs data that vary")


def require_points(model: str, n: int, n_params: int) -> None:
    if n <= n_params:
        raise FitError(f"{model}: {n} point(s) for {n_params} fitted parameter(s); need at least "
                       f"{n_params + 1} to estimate uncertainties")


def require_sigma(model: str, name: str, sigma: np.ndarray | None) -> np.ndarray | None:
    if sigma is None:
        return None
    sigma = require_finite(model, name, sigma)
    bad = sigma <= 0
    if bad.any():
        raise FitError(f"{model}: uncertainties in {name!r} must be positive (data row {_rows(bad)})")
    return sigma
