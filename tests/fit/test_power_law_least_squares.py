"""The one least-squares power law (the live view's fit in ln y, the quick fit's in y):
it recovers a law, agrees with ``labkit fit``'s power law in ln y, weights by sigma, and says
why it cannot fit."""

from __future__ import annotations

import numpy as np
import pytest

from labkit.fit.models.power_law import fit_power_law, least_squares_power_law
from labkit.protocols.quickfit import quick_fit_power_law
from labkit.stream.livefit import power_law_fit

X = np.linspace(6000.0, 20000.0, 8)


@pytest.mark.parametrize("residuals", ["log", "linear"])
def test_both_residual_spaces_recover_an_exact_law(residuals):
    fit = least_squares_power_law(X, 224e6 * X**-1.9, residuals=residuals)
    assert fit.a == pytest.approx(224e6, rel=1e-6) and fit.b == pytest.approx(-1.9, abs=1e-9)
    assert fit.n == 8 and fit.residuals == residuals


def test_in_ln_y_it_is_labkit_fits_power_law_and_the_live_views():
    rng = np.random.default_rng(7)
    y = 224e6 * X**-1.9 * np.exp(0.03 * rng.standard_normal(len(X)))
    mine = least_squares_power_law(X, y, residuals="log")
    theirs = fit_power_law(X, y)
    assert mine.a == pytest.approx(theirs.params["a"].value, rel=1e-8)
    assert mine.b == pytest.approx(theirs.params["b"].value, rel=1e-8)
    assert mine.stderr_b == pytest.approx(theirs.params["b"].stderr, rel=1e-6)
    live = power_law_fit(list(X), list(y))
    assert live.params["b"] == (mine.b, mine.stderr_b)


def test_in_y_a_point_with_a_large_sigma_hardly_counts():
    y = 224e6 * X**-1.9
    outlier = y.copy()
    outlier[0] *= 1.5
    sigma = np.full(len(X), 0.01 * y.min())
    weighted = least_squares_power_law(X, outlier, sigma * np.r_[1e6, np.ones(len(X) - 1)], "linear")
    unweighted = least_squares_power_law(X, outlier, residuals="linear")
    assert abs(weighted.b + 1.9) < 1e-3 < abs(unweighted.b + 1.9)
    quick = quick_fit_power_law(list(X), list(outlier), list(sigma * np.r_[1e6, np.ones(len(X) - 1)]))
    assert quick["params"]["b"]["value"] == weighted.b


def test_it_says_why_it_cannot_fit():
    with pytest.raises(ValueError, match=">= 3 positive points, got 2"):
        least_squares_power_law([6000, 8000, 9000], [1.0, 2.0, -1.0])
    with pytest.raises(ValueError, match="distinct x"):
        least_squares_power_law([6000, 6000, 6000], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="sigma weights only"):
        least_squares_power_law(X, X**-2, sigma=X, residuals="log")
    with pytest.raises(ValueError, match="residuals must be one of log, linear"):
        least_squares_power_law(X, X**-2, residuals="ln")
    assert power_law_fit([6000, 8000], [10.0, 5.0]) is None
