"""Pure error metrics on synthetic data with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.numerics import metrics


@pytest.mark.parametrize("order", [2.0, 4.0, 6.0])
def test_observed_order_of_an_exact_power_law(order):
    steps = [8, 16, 32, 64, 128]
    errors = [3.0 * n**-order for n in steps]
    assert metrics.observed_order(steps, errors) == pytest.approx(order, abs=1e-12)


def test_observed_order_ignores_the_round_off_floor_and_failures():
    steps = [8, 16, 32, 64, 128, 256]
    errors = [1e-3, 6.25e-5, 3.90625e-6, 1e-15, 2e-15, math.nan]  # order 4, then round-off
    assert metrics.observed_order(steps, errors) == pytest.approx(4.0, abs=1e-9)


def test_cost_to_reach_interpolates_a_power_law_exactly():
    # error = cost^-2: reaching 1e-6 costs exactly 1e3 (log-log interpolation is exact here)
    points = [(c, c**-2.0) for c in (10.0, 100.0, 10_000.0)]
    assert metrics.cost_to_reach(points, 1e-6) == pytest.approx(1e3, rel=1e-12)
    assert metrics.cost_to_reach(points, 1e-9) is None  # never reached
    assert metrics.cost_to_reach(points, 1.0) == 10.0  # already reached by the cheapest point


def test_pareto_front_drops_dominated_and_failed_points():
    points = [(1.0, 1e-2), (2.0, 5e-2), (3.0, 1e-4), (4.0, math.nan), (math.nan, 1e-9)]
    assert metrics.pareto_front(points) == [(1.0, 1e-2), (3.0, 1e-4)]


def test_drift_growth_tells_bounded_from_secular():
    t = np.arange(1000.0)
    bounded = 1.0 + 1e-12 * np.sin(0.3 * t)
    secular = 1.0 + 1e-12 * t
    assert metrics.drift_growth(bounded) < 1.5
    assert metrics.drift_growth(secular) > 9.0


def test_stroboscopic_indices_pick_exact_multiples_of_the_period():
    t = np.arange(17) * 0.25 * 0.02  # 4 samples per period of 0.02 s
    assert metrics.stroboscopic_indices(t, 0.02).tolist() == [0, 4, 8, 12, 16]
