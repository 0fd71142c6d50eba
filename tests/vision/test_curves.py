"""Eq. 6.38 parametrisation and the canonical forms the fit reports."""

import math

import numpy as np
import pytest

from labkit.vision.shared.curves import (
    Pattern,
    a_for_k,
    ellipse_from_coefficients,
    k_for,
    rotation_error_deg,
    trochoid_from_coefficients,
)


def eq_6_38(t, a, b):
    """The paper's Eq. 6.38 written out: x = cos t + b cos((1+a)/a t), y = sin t + b sin(...)."""
    r = (1 + a) / a
    return np.column_stack([np.cos(t) + b * np.cos(r * t), np.sin(t) + b * np.sin(r * t)])


@pytest.mark.parametrize("kind,loops", [("epitrochoid", n) for n in range(2, 8)]
                         + [("hypotrochoid", n) for n in range(3, 8)])
def test_pattern_points_follow_eq_6_38(kind, loops):
    k = k_for(kind, loops)
    a = a_for_k(k)
    t = np.linspace(0, 2 * math.pi, 500)
    p = Pattern(kind, (0.0, 0.0), 0.0, scale=1.0, b=0.4, loops=loops)
    np.testing.assert_allclose(p.points(t), eq_6_38(t, a, 0.4), atol=1e-12)


def test_paper_three_armed_hypotrochoid_is_a_minus_one_third():
    # Fig. 6.19 caption: a = -1/3, b = 0.82 draws the three-armed pattern
    assert a_for_k(k_for("hypotrochoid", 3)) == pytest.approx(-1 / 3)
    # the paper: a in (0, 1) gives epitrochoids; 2 loops = a main loop and one small loop
    assert 0 < a_for_k(k_for("epitrochoid", 7)) < a_for_k(k_for("epitrochoid", 2)) <= 1


def test_hypotrochoid_needs_three_loops():
    with pytest.raises(ValueError):
        k_for("hypotrochoid", 2)


def test_ellipse_canonical_form_recovers_axes_and_rotation():
    rot = math.radians(130)
    e = complex(math.cos(rot), math.sin(rot))
    # x' = 50 cos t, y' = 20 sin t rotated by 130 deg, centre (5, 6)
    p = ellipse_from_coefficients(complex(5, 6), e * 35, e * 15)
    assert p.semi_axes == pytest.approx((50, 20))
    assert rotation_error_deg(p.rotation_rad, rot, math.pi) < 1e-9
    pts = p.points(np.linspace(0, 2 * math.pi, 400)) - [5, 6]
    r = np.hypot(*pts.T)
    assert r.max() == pytest.approx(50, rel=1e-4) and r.min() == pytest.approx(20, rel=1e-3)


def test_trochoid_canonical_form_is_invariant_to_reparametrisation():
    p = Pattern("epitrochoid", (10.0, -3.0), 0.3, scale=40.0, b=0.5, loops=4)
    c, a, b, k = p.coefficients()
    tau = 1.234  # shift the curve parameter: the same point set
    q = trochoid_from_coefficients(c, a * np.exp(1j * tau), b * np.exp(1j * k * tau), k)
    assert q.scale == pytest.approx(40) and q.b == pytest.approx(0.5)
    assert rotation_error_deg(q.rotation_rad, 0.3, 2 * math.pi / 3) < 1e-9
