"""Nearest-neighbour queries of the laser analysis, in one place (docs/explanation/vision-throughput.md, *The
whole command*).

:class:`PointTree` is an exact kd-tree over 2-D points (``pykdtree``). It replaces
``scipy.spatial.cKDTree``: the same neighbours and distances (tested), but importing pykdtree
costs about 0.05 s where ``scipy.spatial`` costs 0.23-0.5 s, which ``labkit analyse laser`` paid
before its first frame or, moved into the fit, on the decoding cores. Indices come back as
``np.intp``; a query beyond ``distance_upper_bound`` gives distance ``inf`` and index ``n`` (the
number of points), as scipy's.
"""

from __future__ import annotations

import functools
import os

import numpy as np

#: pykdtree parallelises each query with OpenMP over all cores. Its queries here are small and run
#: while the video decoder keeps both cores busy, so the spinning OpenMP threads cost more than
#: they save: a 720p clip's whole analysis took 3.1 CPU-s with them and 1.3 CPU-s with one thread.
QUERY_THREADS = "1"


@functools.cache
def _kdtree_class():
    """pykdtree's KDTree, its OpenMP runtime started with one thread. OpenMP reads
    OMP_NUM_THREADS once, when the runtime (pykdtree's own bundled libgomp) loads, and applies it
    to every thread; the variable is put back at once, so nothing else in the process (or a child)
    sees the change."""
    saved = os.environ.get("OMP_NUM_THREADS")
    os.environ["OMP_NUM_THREADS"] = QUERY_THREADS
    try:
        from pykdtree.kdtree import KDTree
    finally:
        if saved is None:
            del os.environ["OMP_NUM_THREADS"]
        else:
            os.environ["OMP_NUM_THREADS"] = saved
    return KDTree


def xy_points(points: np.ndarray) -> np.ndarray:
    """(n, 2) float64, C-contiguous: complex points become (re, im) columns."""
    p = np.asarray(points)
    if np.iscomplexobj(p):
        p = np.column_stack([p.real, p.imag])
    return np.ascontiguousarray(p, dtype=np.float64).reshape(-1, 2)


class PointTree:
    """Exact kd-tree over 2-D points (an (n, 2) array or complex points)."""

    def __init__(self, points: np.ndarray) -> None:
        self._points = xy_points(points)
        self.n = len(self._points)
        self._tree = _kdtree_class()(self._points) if self.n else None

    def query(self, points: np.ndarray,
              distance_upper_bound: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
        """Distance to and index of the nearest tree point for each query point."""
        q = xy_points(points)
        if self._tree is None or len(q) == 0:
            return np.full(len(q), np.inf), np.full(len(q), self.n, dtype=np.intp)
        bound = None if not np.isfinite(distance_upper_bound) else float(distance_upper_bound)
        dist, idx = self._tree.query(q, k=1, distance_upper_bound=bound)
        return np.asarray(dist, dtype=np.float64), np.asarray(idx, dtype=np.intp)
