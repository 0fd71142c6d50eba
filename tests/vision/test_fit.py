"""Pattern classification and fit on point clouds with known answers (no video)."""

import math

import numpy as np
import pytest

from labkit.vision.laser.pattern_fit import (
    classify,
    coverage_rms,
    fit_ellipse,
    fit_trochoid,
    pattern_kind,
    two_way_rms,
    without_outliers,
)
from labkit.vision.shared.curves import Pattern, rotation_error_deg


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


def test_coverage_tells_a_curve_with_extra_loops_from_the_right_one():
    """A 7-loop epitrochoid fitted to a 4-loop trace passes near the light (its residual is
    small), but most of its length runs over dark screen: its coverage is tens of px, the true
    curve's is at the noise level."""
    truth = Pattern("epitrochoid", (640.4, 360.7), 0.3, scale=166.0, b=0.3, loops=4)
    pts = cloud(truth, noise=1.0)
    z = pts[:, 0] + 1j * pts[:, 1]
    right, wrong = fit_trochoid(pts, "epitrochoid", 4), fit_trochoid(pts, "epitrochoid", 7)
    no_drift = np.zeros(len(z))
    assert coverage_rms(right, z, no_drift) < 2.0
    assert coverage_rms(wrong, z, no_drift) > 10 * coverage_rms(right, z, no_drift)
    assert two_way_rms(right.rms_residual, coverage_rms(right, z, no_drift)) < two_way_rms(
        wrong.rms_residual, coverage_rms(wrong, z, no_drift))


def test_a_last_refit_without_outliers_removes_their_pull():
    """5 % specks scattered inside an ellipse (compression ringing, halo blobs) pull a least-squares
    fit; the refit without points beyond 3 robust sigmas recovers centre and axes."""
    truth = Pattern("ellipse", (200.0, 150.0), math.radians(30), (90.0, 60.0))
    rng = np.random.default_rng(3)
    specks = np.column_stack([rng.uniform(150, 215, 150), rng.uniform(120, 180, 150)])
    pts = np.vstack([cloud(truth, n=3000, noise=0.7), specks])
    pulled = fit_ellipse(pts)
    clean = without_outliers(pulled, pts)
    error = math.dist(clean.pattern.center, truth.center)
    assert error < 0.1 < math.dist(pulled.pattern.center, truth.center)
    assert clean.pattern.semi_axes == pytest.approx((90, 60), rel=0.005)
    assert clean.rms_residual == pytest.approx(0.7, rel=0.15)  # the noise across the curve
