"""Small loops seen or filled in, tips on the light, and b set by where the light ends
(labkit.vision.laser.loops_seen), on point clouds drawn from the curves of labkit.vision.shared.curves."""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.vision.laser.checks import laser_evidence, laser_verdict
from labkit.vision.laser.loops_seen import cusp_fit, loop_width, tip_gap, tip_limited
from labkit.vision.laser.pattern_fit import Classification, fit_ellipse, fit_trochoid
from labkit.vision.shared.curves import Pattern, k_for


def cloud(p: Pattern, n: int = 3000, noise: float = 0.3, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return p.points(rng.uniform(0, 2 * math.pi, n)) + rng.normal(0, noise, (n, 2))


def brute_force_loop_width(k: int, b: float, scale: float) -> float:
    """The loop's width found without the loop's axis or its symmetry: the polyline of one arm
    (a window of one symmetry step around the loop) is intersected with itself segment by
    segment; between the two parameters of the crossing lies the loop, and its width is its
    extent across the line from the crossing to the loop's farthest point."""
    m = abs(k - 1)
    centre_t = 0.0 if k < 0 else math.pi / m
    t = centre_t + np.linspace(-math.pi / m, math.pi / m, 1201)
    z = scale * (np.exp(1j * t) + b * np.exp(1j * k * t))
    p, d = z[:-1], np.diff(z)
    # segments i and j cross when each one's ends lie on either side of the other
    def side(a, u, q):
        return (np.conj(u) * (q - a)).imag
    s1 = side(p[:, None], d[:, None], p[None, :]) * side(p[:, None], d[:, None], (p + d)[None, :])
    s2 = side(p[None, :], d[None, :], p[:, None]) * side(p[None, :], d[None, :], (p + d)[:, None])
    i, j = np.nonzero(np.triu((s1 < 0) & (s2 < 0), 2))
    if len(i) == 0:
        return 0.0
    inner = np.argmin(j - i)  # the innermost crossing: the small loop's
    loop = z[i[inner]:j[inner] + 2]
    crossing = z[i[inner]]
    far = loop[np.argmax(np.abs(loop - crossing))]
    axis = (far - crossing) / abs(far - crossing)
    across = ((loop - crossing) * np.conj(axis)).imag
    return float(across.max() - across.min())


@pytest.mark.parametrize("kind,loops", [("hypotrochoid", 3), ("hypotrochoid", 6), ("epitrochoid", 3),
                                        ("epitrochoid", 7)])
def test_loops_form_past_k_b_one_and_widen_with_b(kind, loops):
    k = k_for(kind, loops)
    assert loop_width(k, 0.98 / abs(k), 50.0) == 0.0  # |k| b < 1: no loops (Sec. 6.5)
    widths = [loop_width(k, s / abs(k), 50.0) for s in (1.05, 1.3, 2.0)]
    assert 0 < widths[0] < widths[1] < widths[2]
    assert loop_width(k, 1.3 / abs(k), 100.0) == pytest.approx(2 * widths[1], rel=1e-9)


@pytest.mark.parametrize("kind,loops,b", [("hypotrochoid", 3, 0.62), ("hypotrochoid", 5, 0.4),
                                          ("epitrochoid", 4, 0.6)])
def test_loop_width_matches_a_brute_force_measure(kind, loops, b):
    k = k_for(kind, loops)
    assert loop_width(k, b, 50.0) == pytest.approx(brute_force_loop_width(k, b, 50.0), rel=0.03)


def test_barely_formed_loops_are_thinner_than_a_thick_line():
    # |k| b = 1.08, the suite's barely-looped patterns: loops far narrower than a 6-8 px line
    assert loop_width(k_for("hypotrochoid", 3), 0.54, 51.6) < 2.0
    assert loop_width(k_for("hypotrochoid", 7), 0.18, 58.3) < 1.0


def test_tips_of_a_right_fit_lie_on_the_light_and_of_a_grown_fit_beyond_it():
    truth = Pattern("hypotrochoid", (160.0, 120.0), 0.3, scale=50.0, b=0.54, loops=3)
    pts = cloud(truth)
    z = pts[:, 0] + 1j * pts[:, 1]
    right = fit_trochoid(pts, "hypotrochoid", 3)
    assert tip_gap(right, z) < 0.5
    grown = cusp_fit(right, pts, b=0.62)  # loops grown: its tips reach past the light
    assert grown.pattern.b == pytest.approx(0.62)
    assert tip_gap(grown, z) > 10.0


def test_b_is_set_where_the_tips_leave_the_light():
    truth = Pattern("hypotrochoid", (160.0, 120.0), 0.3, scale=50.0, b=0.54, loops=3)
    pts = cloud(truth)
    grown = cusp_fit(fit_trochoid(pts, "hypotrochoid", 3), pts, b=0.62)
    limited = tip_limited(grown, pts, None, None, width=8.0)  # an 8 px line: loops filled in
    assert limited is not None
    assert limited.pattern.b == pytest.approx(0.54, abs=0.02)
    outer = limited.pattern.scale * (1 + limited.pattern.b)
    assert outer == pytest.approx(50.0 * 1.54, rel=0.02)


def test_tip_limit_leaves_right_fits_and_seen_loops_alone():
    truth = Pattern("hypotrochoid", (160.0, 120.0), 0.3, scale=50.0, b=0.54, loops=3)
    pts = cloud(truth)
    right = fit_trochoid(pts, "hypotrochoid", 3)
    assert tip_limited(right, pts, None, None, width=8.0) is None  # tips on the light
    big = Pattern("epitrochoid", (300.0, 200.0), 0.2, scale=80.0, b=0.6, loops=4)
    pts = cloud(big)
    grown = cusp_fit(fit_trochoid(pts, "epitrochoid", 4), pts, b=0.7)
    assert tip_limited(grown, pts, None, None, width=4.0) is None  # loops wide open: seen


def test_the_verdict_says_when_the_tips_lie_beyond_the_light_and_the_loops_are_filled_in():
    truth = Pattern("hypotrochoid", (160.0, 120.0), 0.3, scale=50.0, b=0.54, loops=3)
    pts = cloud(truth)
    right = fit_trochoid(pts, "hypotrochoid", 3)
    grown = cusp_fit(right, pts, b=0.62)

    def checks(fit, width):
        cls = Classification(fit, fit_ellipse(pts))
        return laser_verdict(laser_evidence(cls, pts, None, width, (320, 240)), (320, 240))

    ok = checks(right, 8.0)
    assert ok["checks"]["tips lit"] == "ok" and ok["tip_gap_line_widths"] < 0.5
    thick = checks(grown, 8.0)  # 8 px line: the grown fit's 5.7 px loops have no opening
    assert thick["checks"]["tips lit"] == "doubtful" and thick["verdict"] != "ok"
    assert any("outer tips" in r and "filled in" in r for r in thick["reasons"])
    thin = checks(grown, 2.0)  # a thin line shows the loops: the tips still lie in dark screen
    assert thin["checks"]["tips lit"] == "doubtful"
    assert not any("filled in" in r for r in thin["reasons"])
