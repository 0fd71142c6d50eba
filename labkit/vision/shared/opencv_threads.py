"""OpenCV's own thread pool: off for a stretch of small image operations, and the precise distance
transform computed the same way whatever the pool's size.

OpenCV splits a blur, a morphology or a resize of a few hundred thousand pixels over its thread
pool, whose workers wait actively after each job. While a video decodes, the decoder keeps both
cores busy, and that splitting and waiting costs CPU the decoder needed (laser trace extraction at
720p: see docs/explanation/vision-throughput.md). Those operations give the same pixels whichever
thread computes them.

The precise Euclidean distance transform does not: OpenCV computes it with its own exact algorithm
when its pool has more than one thread, and with IPP's otherwise (or for an image under 16384
pixels), and IPP's differs in the last bit at some pixels (sqrt(37): 6.0827622 against the correctly
rounded 6.0827627; opencv/opencv#24082). :func:`precise_distance_transform` therefore runs it with a
pool of at least two threads, on every machine, so the answer does not depend on the number of cores
or on a caller's ``cv2.setNumThreads``.

``cv2.setNumThreads`` is global to the process, so the sections here are counted under one lock:
nested or concurrent :func:`one_opencv_thread` sections share one switch (the count saved by the
first is restored by the last), and a distance transform holds the lock while it runs. OpenCV calls
in other threads during a section run on one thread as well: the same pixels for every operation
but the precise distance transform, which therefore goes through :func:`precise_distance_transform`
everywhere in labkit. A video's decoder threads are FFmpeg's, not OpenCV's pool.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

import cv2
import numpy as np

_LOCK = threading.Lock()
_state = {"depth": 0, "saved": 1}


@contextmanager
def one_opencv_thread() -> Iterator[None]:
    """Run the body with OpenCV's thread pool set to one thread; the count before is restored
    when the last of any overlapping sections ends."""
    with _LOCK:
        if _state["depth"] == 0:
            _state["saved"] = cv2.getNumThreads()
            if _state["saved"] != 1:
                cv2.setNumThreads(1)
        _state["depth"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _state["depth"] -= 1
            if _state["depth"] == 0 and _state["saved"] != 1:
                cv2.setNumThreads(_state["saved"])


def precise_distance_transform(mask: np.ndarray) -> np.ndarray:
    """``cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)`` (float32, exact
    Euclidean distance to the nearest zero pixel) from OpenCV's own algorithm on every machine:
    its pool is set to at least two threads for the call (inside a :func:`one_opencv_thread`
    section too); an image under 16384 pixels goes to IPP's algorithm whatever the pool, as in
    OpenCV itself."""
    with _LOCK:
        current = cv2.getNumThreads()
        if current < 2:
            cv2.setNumThreads(2)
        try:
            return cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        finally:
            if current < 2:
                cv2.setNumThreads(current)
