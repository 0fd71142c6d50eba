"""labkit.vision.laser.nearest.PointTree: exact nearest neighbours, checked against brute force."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from labkit.vision.laser.nearest import PointTree

coords = st.floats(-2000, 2000, allow_nan=False, width=64)
clouds = st.integers(1, 60).flatmap(lambda n: arrays(np.float64, (n, 2), elements=coords))


@settings(max_examples=80, deadline=None)
@given(clouds, clouds, st.floats(0.1, 500))
def test_nearest_distances_are_the_brute_force_ones(points, queries, bound):
    brute = np.hypot(*(queries[:, None, :] - points[None, :, :]).transpose(2, 0, 1)).min(axis=1)
    dist, idx = PointTree(points).query(queries)
    np.testing.assert_allclose(dist, brute, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(np.hypot(*(queries - points[idx]).T), brute, rtol=1e-12, atol=1e-9)
    assert idx.dtype == np.intp
    far_dist, far_idx = PointTree(points).query(queries, distance_upper_bound=bound)
    beyond = brute > bound * (1 + 1e-9)
    assert np.all(np.isinf(far_dist[beyond])) and np.all(far_idx[beyond] == len(points))
    within = brute < bound * (1 - 1e-9)
    np.testing.assert_allclose(far_dist[within], brute[within], rtol=1e-12, atol=1e-9)


def test_complex_points_and_empty_sets():
    z = np.array([0 + 0j, 3 + 4j])
    dist, idx = PointTree(z).query(np.array([3 + 3.5j]))
    assert idx.tolist() == [1] and abs(dist[0] - 0.5) < 1e-12
    dist, idx = PointTree(np.zeros((0, 2))).query(z)
    assert np.all(np.isinf(dist)) and np.all(idx == 0)
    assert PointTree(z).query(np.zeros((0, 2)))[0].shape == (0,)


def test_the_tree_leaves_the_environment_as_it_was():
    import os

    before = os.environ.get("OMP_NUM_THREADS")
    PointTree(np.zeros((3, 2))).query(np.ones((2, 2)))
    assert os.environ.get("OMP_NUM_THREADS") == before


@settings(max_examples=80, deadline=None)
@given(clouds, clouds, st.floats(0.1, 500))
def test_a_search_bound_leaves_every_distance_within_it_exactly_as_it_was(points, queries, bound):
    """labkit.vision.laser.wander prunes its coverage test (distance <= width) with a bound of twice
    the width; that gives the same answer only if the bound changes no distance within it, not
    even in the last bit."""
    free_dist, free_idx = PointTree(points).query(queries)
    dist, idx = PointTree(points).query(queries, distance_upper_bound=bound)
    found = np.isfinite(dist)
    assert np.array_equal(dist[found], free_dist[found]) and np.array_equal(idx[found], free_idx[found])
    inside = free_dist < bound
    assert np.all(found[inside]) and np.array_equal((dist <= 0.5 * bound), (free_dist <= 0.5 * bound))
