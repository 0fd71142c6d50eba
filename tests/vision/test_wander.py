"""Following a wandering camera chunk by chunk (labkit.vision.laser.wander), on point clouds with a
known centre path: chunks the camera moved by several line widths off a straight drift are
registered too."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.vision.laser.nearest import PointTree
from labkit.vision.laser.pattern_fit import classify
from labkit.vision.laser.wander import follow_wander, lit_samples
from labkit.vision.shared.curves import Pattern

WIDTH = 4.0
MIDS = (np.arange(8) + 0.5) * 0.25  # eight chunks of a 2 s clip


def centre_path(t: np.ndarray) -> np.ndarray:
    """A tripod drifting 10 px/s and wandering 14 px at 0.35 Hz (3.5 line widths)."""
    return (10 + 4j) * (t - 1.0) + 14 * (np.sin(2 * math.pi * 0.35 * t + 0.4)
                                         + 1j * np.cos(2 * math.pi * 0.35 * t + 1.1))


def wandering_trace(pattern: Pattern, seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """Points of ``pattern`` per chunk: 600 points on a random 70 % of the curve (the middle
    chunk: all of it), moved by the centre path at the chunk's time, with 0.4 px noise; and each
    point's chunk time."""
    rng = np.random.default_rng(seed)
    pts, times = [], []
    for j, t in enumerate(MIDS):
        start = rng.uniform(0, 2 * math.pi)
        s = start + rng.uniform(0, (1.0 if j == 4 else 0.7) * 2 * math.pi, 600)
        z = pattern.points(s) @ np.array([1, 1j]) + centre_path(np.array([t]))[0]
        z = z + rng.normal(0, 0.4, len(z)) + 1j * rng.normal(0, 0.4, len(z))
        pts.append(np.column_stack([z.real, z.imag]))
        times.append(np.full(len(z), t))
    return np.concatenate(pts), np.concatenate(times)


def test_chunks_moved_several_line_widths_off_a_straight_drift_are_all_registered():
    truth = Pattern("epitrochoid", (320.0, 240.0), 0.3, scale=110.0, b=0.35, loops=5)
    points, times = wandering_trace(truth)
    # start as the analysis does when the whole trace is a blur: the middle chunk alone
    middle = times == MIDS[4]
    start = replace(classify(points[middle], None, None), t_ref=float(MIDS[4]))
    assert start.best.pattern.loops == 5
    wander = follow_wander(start, points, None, times, WIDTH)
    assert wander is not None and wander.needed
    assert wander.chunks_checked == len(MIDS)
    want = complex(*truth.center) + centre_path(MIDS)
    got = np.array([wander.centre_at(t) for t in MIDS])
    assert np.max(np.abs(got - want)) < 0.5 * WIDTH, np.abs(got - want)
    assert abs(wander.centre_at(1.0) - (complex(*truth.center) + centre_path(np.array([1.0]))[0])) < 1.0
    assert abs(wander.fit.pattern.scale / truth.scale - 1) < 0.01


def ellipse_band(points: np.ndarray, times: np.ndarray, seed: int = 9) -> tuple:
    """A trace band around centre-line points: each point spread across a 4 px wide line."""
    rng = np.random.default_rng(seed)
    band = points + rng.uniform(-WIDTH / 2, WIDTH / 2, points.shape)
    return band, np.ones(len(band)), times


def test_an_ellipse_is_polished_on_the_band_only_when_its_wander_is_needed():
    """The band polish changes the fit of a wandering ellipse; a steady one's fit is the same with
    and without the band (its straight-drift fit is kept by the analysis, so the polish is not
    done), and the decision and offsets never depend on the band."""
    truth = Pattern("ellipse", (400.0, 300.0), 0.4, semi_axes=(150.0, 60.0))
    wandering, times = wandering_trace(truth)
    steady_rng = np.random.default_rng(2)
    z = truth.points(steady_rng.uniform(0, 2 * math.pi, len(times))) @ np.array([1, 1j])
    noise = steady_rng.normal(0, 0.4, len(z)) + 1j * steady_rng.normal(0, 0.4, len(z))
    z = z + (3 + 1j) * (times - 1.0) + noise
    steady = np.column_stack([z.real, z.imag])
    outcomes = {}
    for name, points in (("wandering", wandering), ("steady", steady)):
        start = classify(points, None, times)
        plain = follow_wander(start, points, None, times, WIDTH)
        banded = follow_wander(start, points, None, times, WIDTH, ellipse_band(points, times))
        assert plain.needed == banded.needed and np.array_equal(plain.offsets, banded.offsets)
        outcomes[name] = (banded.needed, banded.fit == plain.fit)
    assert outcomes == {"wandering": (True, False), "steady": (False, True)}


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), loops=st.sampled_from([1, 3, 5]), arc=st.floats(0.05, 1.0),
       count=st.integers(1, 400), width=st.floats(0.5, 20.0), spread=st.floats(0.0, 30.0))
def test_lit_samples_are_the_samples_with_light_within_a_width(seed, loops, arc, count, width, spread):
    """The shortcut of ``lit_samples`` against every sample-to-point distance: the same samples,
    for traces that show part or all of the curve, points on it, beside it and far off, crossings."""
    rng = np.random.default_rng(seed)
    pattern = (Pattern("ellipse", (300.0, 200.0), 0.4, semi_axes=(120.0, 40.0)) if loops == 1 else
               Pattern("epitrochoid", (300.0, 200.0), 0.4, scale=100.0, b=0.4, loops=loops))
    t = np.linspace(0, 2 * math.pi, 2000, endpoint=False)
    curve = pattern.points(t) @ np.array([1, 1j])
    s = rng.uniform(0, arc * 2 * math.pi, count)
    noise = rng.normal(0, spread, count) + 1j * rng.normal(0, spread, count)
    points = pattern.points(s) @ np.array([1, 1j]) + noise
    dist, idx = PointTree(curve).query(points)
    want = np.min(np.abs(curve[:, None] - points[None, :]), axis=1) <= width
    assert np.array_equal(lit_samples(curve, points, dist, idx, width), want)
