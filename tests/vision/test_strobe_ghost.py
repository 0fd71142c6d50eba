"""The room-light model of labkit.vision.strobe.room_light on pictures made here: a bar swung through
a known revolution, blurred by a known lens, with a known share of room light."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.vision.strobe.body import measure_flat
from labkit.vision.strobe.room_light import _blur_basis, fit_room_light, linear_darkening, revolution_average

SIZE = 96


def _bar(angle: float, centre=(48.0, 48.0), length=40.0, width=12.0) -> np.ndarray:
    """Coverage (0..1) of a bar whose long axis is ``angle`` from image +x towards +y."""
    u = np.array([math.cos(angle), math.sin(angle)]) * length / 2
    v = np.array([-math.sin(angle), math.cos(angle)]) * width / 2
    c = np.asarray(centre)
    corners = np.array([c + u + v, c + u - v, c - u - v, c - u + v])
    big = np.zeros((SIZE * 8, SIZE * 8), np.uint8)
    cv2.fillPoly(big, [np.round(((corners + 0.5) * 8 - 0.5) * 16).astype(np.int32)], 255, cv2.LINE_8, 4)
    return cv2.resize(big.astype(np.float32) / 255.0, (SIZE, SIZE), interpolation=cv2.INTER_AREA)


def _lens(cover: np.ndarray) -> np.ndarray:
    """A core and a halo holding a quarter of the light."""
    return 0.75 * cv2.GaussianBlur(cover, (0, 0), 1.2) + 0.25 * cv2.GaussianBlur(cover, (0, 0), 5.0)


def test_a_positive_tilt_turns_the_body_clockwise_on_screen():
    """The tilt convention of labkit.vision.strobe.body.ClipOrientation: positive turns the top
    towards the normal, clockwise on screen, so the moment angle (from +x towards +y) grows."""
    image = _lens(_bar(0.3))
    turned = revolution_average(image, (48.0, 48.0), 0.0, np.array([0.2]))
    before = measure_flat((200 * (1 - image)).astype(np.float32))
    after = measure_flat((200 * (1 - turned)).astype(np.float32))
    assert math.remainder(after.angle2_rad - before.angle2_rad, math.pi) == pytest.approx(0.2, abs=0.01)


@settings(max_examples=15, deadline=None)
@given(a=st.floats(0.0, 0.45), phi=st.floats(0.08, 0.25), seed=st.integers(0, 2**16))
def test_the_room_light_share_comes_back(a, phi, seed):
    """Frames ``(1 - a) c_k + a h_k`` with the ghost ``h_k`` of the bar's own revolution about a
    point beside it, plus sensor noise: the fitted share is within 0.02 of ``a`` for swings of
    0.15 rad and more, 0.06 down to 0.08 rad, with the lens
    (a core and a halo holding a quarter of the light, which thins the bar's half-coverage
    outline) fitted too."""
    rng = np.random.default_rng(seed)
    revolution = phi * np.sin(2 * math.pi * (np.arange(24) + 0.5) / 24)
    centre = (48.0, 30.0)
    d, h, w, basis = [], [], [], []
    for psi in np.linspace(0, 2 * math.pi, 8, endpoint=False):
        tilt = phi * math.sin(psi)
        rest = _lens(_bar(0.0))
        cover = revolution_average(rest, centre, 0.0, np.array([tilt]))
        ghost = revolution_average(cover, centre, tilt, revolution)
        frame = (1 - a) * cover + a * ghost + rng.normal(0, 0.01, cover.shape).astype(np.float32)
        d.append(frame.ravel())
        h.append(ghost.ravel())
        w.append(np.ones(frame.size, np.float32))
        basis.append(_blur_basis(cover))
    d, h, w, basis = (np.concatenate(x) for x in (d, h, w, basis))
    alpha, mix = fit_room_light(d, h, w, basis)
    assert alpha == pytest.approx(a, abs=0.02 if phi >= 0.15 else 0.06)
    model = (1 - alpha) * (basis @ mix) + alpha * h  # explains the frames down to their noise
    assert float(np.sqrt(np.mean((d - model) ** 2))) < 0.015


def test_linear_darkening_undoes_the_encoding_and_the_lamp():
    """A dark body at half coverage on a background twice as bright on the right: the darkening
    reads 0 on the background and 0.9 x coverage on the body, on both sides."""
    x = np.linspace(0, 1, 200, dtype=np.float32)
    background = 0.3 * (1 + x)[None, :] * np.ones((100, 1), np.float32)
    cover = np.zeros((100, 200), np.float32)
    cover[40:60, 20:30] = 0.5
    cover[40:60, 170:180] = 1.0
    linear = background * (1 - 0.9 * cover)
    gray = np.round(linear ** (1 / 2.2) * 255).astype(np.uint8)
    d, rows = linear_darkening(gray, dark=True)
    assert abs(float(np.median(d[:30]))) < 0.01
    assert float(d[50, 25]) == pytest.approx(0.45, abs=0.02)
    assert float(d[50, 175]) == pytest.approx(0.9, abs=0.02)
    assert rows.shape == (100,)
