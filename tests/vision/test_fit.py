"""Pattern classification and fit on point clouds with known answers (no video)."""

import math

import numpy as np
import pytest

from labkit.vision.curves import Pattern, rotation_error_deg
from labkit.vision.fit import classify, fit_ellipse, pattern_kind


def cloud(pattern, n=2500, noise=1.0, seed=0):
    rng = np.random.default_rng(seed)
    return pattern.points(rng.uniform(0, 2 * math.pi, n)) + rng.normal(0, noise, (n, 2))


# loop counts not covered by the video acceptance set (which has epi 2, 4, 7 and hypo 3, 5, 6)
@pytest.mark.parametrize("kind,loops,b,rot", [
    ("epitrochoid", 3, 0.6, 0.1), ("epitrochoid", 5, 0.25, 1.0), ("epitrochoid", 6, 0.2, 0.3),
    ("hypotrochoid", 4, 0.45, 0.7), ("hypotrochoid", 7, 0.3, 0.2),
])
def test_trochoid_loops_and_parameters(kind, loops, b, rot):
    truth = Pattern(kind, (300.4, 200.7), rot, scale=100.0, b=b, loops=loops)
    best = classify(cloud(truth)).best
    assert pattern_kind(best) == kind
    assert best.pattern.loops == loops
    assert abs(best.pattern.b - b) < 0.05
    assert math.dist(best.pattern.center, truth.center) < 1.0
    assert rotation_error_deg(best.pattern.rotation_rad, rot, 2 * math.pi / abs(truth.k - 1)) < 2.0


def test_ellipse_with_linear_drift_of_the_centre():
    truth = Pattern("ellipse", (200.0, 150.0), math.radians(70), (90.0, 45.0))
    rng = np.random.default_rng(1)
    t = rng.uniform(0, 2 * math.pi, 3000)
    times = rng.uniform(0, 4.0, 3000)
    pts = truth.points(t) + np.outer(times - times.mean(), [2.5, -1.5]) + rng.normal(0, 0.7, (3000, 2))
    fit = fit_ellipse(pts, times=times)
    assert math.dist(fit.pattern.center, truth.center) < 0.3
    assert fit.drift.real == pytest.approx(2.5, abs=0.1) and fit.drift.imag == pytest.approx(-1.5, abs=0.1)
    assert fit.pattern.semi_axes == pytest.approx((90, 45), rel=0.01)


def test_circle_is_reported_as_circle():
    best = classify(cloud(Pattern("circle", (100.0, 100.0), 0.0, (60.0, 60.0)), n=1500)).best
    assert pattern_kind(best) == "circle"


def test_too_few_points_is_a_value_error():
    with pytest.raises(ValueError):
        fit_ellipse(np.zeros((5, 2)))


def test_a_prior_from_too_little_of_the_trace_is_screened_again():
    # the first part of a clip seen at a large stride can look like another trochoid; refined on the
    # whole trace its choice fits far worse than it fitted the part, so every candidate is screened
    truth = Pattern("hypotrochoid", (300.4, 200.7), 0.4, scale=100.0, b=0.3, loops=4)
    misleading = classify(cloud(Pattern("hypotrochoid", (300.4, 200.7), 0.4, scale=100.0, b=0.3, loops=6)))
    assert misleading.best.pattern.loops == 6
    best = classify(cloud(truth), prior=misleading).best
    assert pattern_kind(best) == "hypotrochoid" and best.pattern.loops == 4
    assert abs(best.pattern.b - 0.3) < 0.05


def test_a_prior_that_explains_the_whole_trace_is_kept():
    truth = Pattern("epitrochoid", (300.4, 200.7), 0.2, scale=100.0, b=0.25, loops=5)
    prior = classify(cloud(truth, seed=1))
    best = classify(cloud(truth, seed=2), prior=prior).best
    assert pattern_kind(best) == "epitrochoid" and best.pattern.loops == 5
    assert "epitrochoid-5 (first part)" in classify(cloud(truth, seed=2), prior=prior).residuals
