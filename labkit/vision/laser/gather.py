"""The trace points of all time chunks of a laser clip, gathered chunk by chunk as each chunk's
trace is extracted (:mod:`labkit.vision.laser.analyse`), so that the work is done in the extraction
worker while later frames decode instead of after the last frame. Pure bookkeeping, no I/O.

Each chunk's points are stamped with the chunk's mid time; seeded subsampling keeps at most
``MAX_POINTS_PER_CHUNK`` centre-line points and ``2 x MAX_POINTS_PER_CHUNK`` band pixels per
chunk. One random generator serves the chunks in order, so gathering chunk by chunk gives
exactly what gathering them all at once gives (:func:`gather`), and the first ``n`` chunks of a
:class:`GatheredTrace` are exactly :func:`gather` of those ``n`` chunks.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np

from labkit.vision.laser.trace import TracePoints

MAX_POINTS_PER_CHUNK = 4000


class ChunkSpan(Protocol):
    """What gathering needs of a chunk: the indices of its first and last frame."""

    first: int
    last: int


class Gathered(NamedTuple):
    """Trace points of the chunks gathered: ``points`` (N, 2), ``weights``, ``times`` (each
    point's chunk mid time, s), ``band`` (pixels, weights, times) or None, and the largest
    ``peak`` and ``noise`` of the chunks."""

    points: np.ndarray
    weights: np.ndarray
    times: np.ndarray
    band: tuple[np.ndarray, np.ndarray, np.ndarray] | None
    peak: float
    noise: float


class GatheredTrace:
    """Chunks' trace points added one chunk at a time, in the chunks' order (:meth:`add`)."""

    def __init__(self, fps: float) -> None:
        self.fps = fps
        # created at the first chunk, in the worker: numpy.random's import (13 ms) then runs
        # while frames decode, not before the first frame (the same seeded draws either way)
        self._rng: np.random.Generator | None = None
        self._parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self._bands: list[tuple[int, tuple[np.ndarray, np.ndarray, np.ndarray]]] = []  # (chunk, band)
        self._levels: list[tuple[float, float]] = []

    def __len__(self) -> int:
        return len(self._parts)

    def add(self, chunk: ChunkSpan, trace: TracePoints) -> None:
        """Add the next chunk's trace."""
        points, weights = trace.points, trace.weights
        if self._rng is None:
            self._rng = np.random.default_rng(0)
        if len(points) > MAX_POINTS_PER_CHUNK:
            keep = self._rng.choice(len(points), MAX_POINTS_PER_CHUNK, replace=False)
            points, weights = points[keep], weights[keep]
        t_mid = 0.5 * (chunk.first + chunk.last) / self.fps if self.fps else 0.0
        if trace.band is not None and trace.band_weights is not None and len(trace.band):
            keep = self._rng.choice(len(trace.band), min(len(trace.band), 2 * MAX_POINTS_PER_CHUNK),
                                    replace=False)
            band = (trace.band[keep], trace.band_weights[keep], np.full(len(keep), t_mid))
            self._bands.append((len(self._parts), band))
        self._parts.append((points, weights, np.full(len(points), t_mid)))
        self._levels.append((trace.peak, trace.noise))

    def result(self, chunks: int | None = None) -> Gathered:
        """The first ``chunks`` chunks' points (default: all added so far)."""
        n = len(self._parts) if chunks is None else chunks
        parts = self._parts[:n]
        bands = [band for index, band in self._bands if index < n]
        peak = max([0.0] + [p for p, _ in self._levels[:n]])
        noise = max([0.0] + [q for _, q in self._levels[:n]])
        if not parts:
            return Gathered(np.zeros((0, 2)), np.zeros(0), np.zeros(0), None, peak, noise)
        points, weights, times = (np.concatenate(column) for column in zip(*parts, strict=True))
        band = None
        if bands:
            band_points, band_weights, band_times = (np.concatenate(column)
                                                     for column in zip(*bands, strict=True))
            band = (band_points, band_weights, band_times)
        return Gathered(points, weights, times, band, peak, noise)


def gather(chunks: list[ChunkSpan], traces: list[TracePoints], fps: float) -> Gathered:
    """Trace points of all ``chunks`` at once (see the module docstring)."""
    gathered = GatheredTrace(fps)
    for chunk, trace in zip(chunks, traces, strict=True):
        gathered.add(chunk, trace)
    return gathered.result()
