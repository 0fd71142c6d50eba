"""The background's opening by a disc as row runs equals OpenCV's opening pixel for pixel."""

from __future__ import annotations

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.vision.laser.disc_opening import open_by_disc


def _opencv(image, kernel):
    return cv2.morphologyEx(image, cv2.MORPH_OPEN, kernel, borderType=cv2.BORDER_REPLICATE)


@settings(max_examples=120, deadline=None)
@given(st.integers(1, 35).map(lambda n: 2 * n + 1), st.integers(1, 140), st.integers(1, 140),
       st.integers(0, 2**31 - 1), st.booleans())
def test_opening_by_a_disc_equals_opencv(k, h, w, seed, smooth):
    """Random grey levels or smooth light with thin bright lines (as a background image), any
    size against the disc, down to one pixel."""
    rng = np.random.default_rng(seed)
    if smooth:
        image = cv2.GaussianBlur(rng.integers(0, 256, (h, w)).astype(np.uint8), (0, 0), 3.0)
        image[rng.integers(0, h, 3), :] = 250
    else:
        image = rng.integers(0, 256, (h, w)).astype(np.uint8)
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    assert np.array_equal(open_by_disc(image, disc), _opencv(image, disc))


def test_rows_of_different_widths_in_any_order_and_other_shapes():
    """An element of centred runs that is not symmetric top to bottom is taken as OpenCV takes it;
    an element with an off-centre run, a gap or an empty row goes to OpenCV."""
    rng = np.random.default_rng(5)
    image = rng.integers(0, 256, (60, 70)).astype(np.uint8)
    uneven = np.zeros((5, 7), np.uint8)
    for row, half in enumerate([0, 1, 3, 2, 1]):
        uneven[row, 3 - half:4 + half] = 1
    others = [np.array([[0, 1, 1], [1, 1, 1], [0, 1, 0]], np.uint8),  # off-centre run
              np.array([[1, 0, 1], [1, 1, 1], [0, 1, 0]], np.uint8),  # a gap
              np.array([[0, 0, 0], [1, 1, 1], [0, 0, 0]], np.uint8),  # empty rows
              np.ones((4, 5), np.uint8)]  # even size
    for kernel in [uneven, *others]:
        assert np.array_equal(open_by_disc(image, kernel), _opencv(image, kernel))
