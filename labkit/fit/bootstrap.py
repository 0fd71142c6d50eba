"""Case-resampling bootstrap: refit on rows drawn with replacement, percentile 95 % intervals.

A cross-check on the covariance intervals for small or non-Gaussian data sets; seeded, so the
same call gives the same intervals.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from labkit.errors import FitError
from labkit.fit.result import FitResult


def bootstrap(fit: Callable[[dict[str, np.ndarray]], FitResult], data: dict[str, np.ndarray],
              result: FitResult, *, n: int = 1000, seed: int = 0,
              on_progress: Callable[[int, int], None] | None = None) -> FitResult:
    """Return ``result`` with ``bootstrap_ci95`` filled for every fitted or derived parameter.
    ``on_progress(done, n)`` is called after each resample (``labkit fit`` prints progress lines)."""
    rng = np.random.default_rng(seed)
    m = len(next(iter(data.values())))
    draws: dict[str, list[float]] = {k: [] for k, p in result.params.items() if not p.fixed}
    failed = 0
    for done in range(1, n + 1):
        if on_progress is not None:
            on_progress(done - 1, n)
        idx = rng.integers(0, m, m)
        try:
            r = fit({k: v[idx] for k, v in data.items()})
        except FitError:
            failed += 1
            continue
        for k in draws:
            draws[k].append(r.params[k].value)
    if n - failed < 20:
        raise FitError(f"{result.model}: bootstrap failed on {failed} of {n} resamples; too few points")
    params = {}
    for k, p in result.params.items():
        if k in draws:
            lo, hi = np.percentile(draws[k], [2.5, 97.5])
            p = replace(p, bootstrap_ci95=(float(lo), float(hi)))
        params[k] = p
    warns = list(result.warnings)
    if failed > 0.05 * n:
        warns.append(f"bootstrap: {failed} of {n} resamples could not be fitted; the intervals are "
                     "biased toward the well-behaved resamples")
    return replace(result, params=params, warnings=tuple(warns))
