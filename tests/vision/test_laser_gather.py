"""Gathering the chunks' trace points chunk by chunk (labkit.vision.laser.gather), as the laser
analysis does in its worker while later frames decode, gives exactly what gathering them all at
once gives, and the first chunks alone what gathering only those gives."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.vision.laser.gather import MAX_POINTS_PER_CHUNK, GatheredTrace, gather
from labkit.vision.laser.trace import TracePoints


@dataclass
class Span:
    first: int
    last: int


def chunk_traces(sizes: list[tuple[int, int]], seed: int) -> tuple[list[Span], list[TracePoints]]:
    """Chunks of 15 frames with ``(centre-line points, band pixels)`` of the given sizes."""
    rng = np.random.default_rng(seed)
    chunks, traces = [], []
    for j, (n, m) in enumerate(sizes):
        band = rng.uniform(0, 720, (m, 2)) if m else None
        band_weights = None if band is None else rng.uniform(1, 9, m)
        traces.append(TracePoints(rng.uniform(0, 720, (n, 2)), rng.uniform(1, 50, n),
                                  float(rng.uniform(20, 200)), float(rng.uniform(1, 5)), band, band_weights))
        chunks.append(Span(15 * j, 15 * j + 14))
    return chunks, traces


def same(a, b) -> bool:
    if a is None or b is None:
        return a is b
    if isinstance(a, tuple):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and np.array_equal(a, b)
    return a == b


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 2 * MAX_POINTS_PER_CHUNK), st.integers(0, 3 * MAX_POINTS_PER_CHUNK)),
                min_size=1, max_size=6), st.integers(0, 2**16))
def test_chunk_by_chunk_equals_all_at_once_and_every_first_part(sizes, seed):
    chunks, traces = chunk_traces(sizes, seed)
    incremental = GatheredTrace(30.0)
    for chunk, trace in zip(chunks, traces, strict=True):
        incremental.add(chunk, trace)
    assert len(incremental) == len(chunks)
    assert same(tuple(incremental.result()), tuple(gather(chunks, traces, 30.0)))
    for n in range(1, len(chunks) + 1):
        assert same(tuple(incremental.result(n)), tuple(gather(chunks[:n], traces[:n], 30.0)))


def test_points_are_capped_per_chunk_and_stamped_with_the_chunk_mid_time():
    chunks, traces = chunk_traces([(9000, 20000), (100, 0), (0, 50)], seed=1)
    got = gather(chunks, traces, 30.0)
    counts = [MAX_POINTS_PER_CHUNK, 100, 0]
    assert len(got.points) == len(got.weights) == len(got.times) == sum(counts)
    assert np.array_equal(np.unique(got.times), [7 / 30, 22 / 30])  # (first + last) / 2 / fps
    assert len(got.band[0]) == 2 * MAX_POINTS_PER_CHUNK + 50
    assert set(np.unique(got.band[2])) == {7 / 30, 37 / 30}
    # the points kept are points of the chunk, each once, with their own weights
    first = traces[0]
    rows = {tuple(p): w for p, w in zip(first.points, first.weights, strict=True)}
    kept = got.points[:MAX_POINTS_PER_CHUNK]
    assert len({tuple(p) for p in kept}) == MAX_POINTS_PER_CHUNK
    assert all(rows[tuple(p)] == w for p, w in zip(kept, got.weights[:MAX_POINTS_PER_CHUNK], strict=True))
    assert got.peak == max(t.peak for t in traces) and got.noise == max(t.noise for t in traces)
