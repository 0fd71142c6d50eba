"""The room light's normal equations accumulated frame by frame (labkit.vision.strobe.room_light_fit)
give the fit that every pixel stacked at once gives: checked against a plain alternation written
here from the model ``d = (1 - a) B p + a h``, ``a = alpha w`` (each step a least-squares solve
over all pixels), on frames whose rows see different light."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.vision.strobe.room_light_fit import ALPHA_TOL, NormalSums, fit_room_light


def _plain_alternation(d, h, w, b, rounds=400):
    alpha = 0.0
    for _ in range(rounds):
        a = np.clip(alpha * w, 0.0, 0.9)
        p, *_ = np.linalg.lstsq(b * (1 - a)[:, None], d - a * h, rcond=None)
        g = b @ p
        x = w * (h - g)
        alpha, before = float(x @ (d - g)) / float(x @ x), alpha
        if abs(alpha - before) < ALPHA_TOL / 10:
            break
    return alpha, p


def _frames(share: float, seed: int, count: int = 5, pixels: int = 900, columns: int = 6):
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(count):
        b = rng.random((pixels, columns))
        p = rng.random(columns) / columns
        h = rng.random(pixels)
        w = np.repeat(rng.uniform(0.8, 1.25, pixels // 30), 30)  # rows that saw more or fewer flashes
        d = (1 - share * w) * (b @ p) + share * w * h + rng.normal(0, 0.005, pixels)
        frames.append((d, h, w, b))
    return frames


@settings(max_examples=20, deadline=None)
@given(share=st.floats(0.0, 0.6), seed=st.integers(0, 2**16))
def test_frame_by_frame_sums_fit_what_all_pixels_at_once_fit(share, seed):
    frames = _frames(share, seed)
    sums = NormalSums(frames[0][3].shape[1])
    for frame in frames:
        sums.add(*frame)
    alpha, mix = sums.solve()
    d, h, w, b = (np.concatenate(column) for column in zip(*frames, strict=True))
    plain_alpha, plain_mix = _plain_alternation(d, h, w, b)
    assert alpha == pytest.approx(plain_alpha, abs=1e-4)
    assert np.allclose(b @ mix, b @ plain_mix, atol=1e-3)
    assert alpha == pytest.approx(share, abs=0.03)  # and it is the share the frames were made with
    once = fit_room_light(d, h, w, b)  # the same sums formed in one call
    assert once[0] == pytest.approx(alpha, abs=1e-9)


def test_no_pixels_no_room_light():
    sums = NormalSums(4)
    sums.add(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros((0, 4)))
    alpha, mix = sums.solve()
    assert alpha == 0.0 and not mix.any() and sums.pixels == 0
