"""Light fixed in the frame while the pattern moves (labkit.vision.laser.second_reading): a timestamp
burnt into every frame stays at the same pixels; arcs of a pattern filmed by a moving camera do not."""

from __future__ import annotations

import math

import numpy as np

from labkit.vision.laser.second_reading import fixed_in_frame, pattern_moved_px, without_fixed_light

CHUNKS = 8
DRIFT = complex(3.0, -1.5)  # px per chunk


def _clip(seed: int = 0):
    """Points of 8 chunks: 6 short arcs of a circle of radius 150 px moving with ``DRIFT`` per
    chunk, and a row of text (fixed strokes plus one character that changes every chunk) at the
    bottom, identical to 0.05 px in every chunk."""
    rng = np.random.default_rng(seed)
    text_x = np.concatenate([np.arange(20.0, 120.0, 0.5), np.arange(130.0, 200.0, 0.5)])
    text = np.column_stack([text_x, 450.0 + 4.0 * np.sin(text_x)])
    pts, times = [], []
    for j in range(CHUNKS):
        t = np.concatenate([np.linspace(a, a + 0.25, 120) for a in np.arange(6) * (2 * math.pi / 6)])
        arcs = complex(320, 220) + DRIFT * j + 150 * np.exp(1j * t)
        changing = np.column_stack([np.full(20, 205.0 + j % 3), np.linspace(444.0, 456.0, 20)])
        still_text = text + rng.normal(0, 0.05, text.shape)
        chunk = np.concatenate([np.column_stack([arcs.real, arcs.imag]), still_text, changing])
        pts.append(chunk)
        times.append(np.full(len(chunk), 0.25 * j + 0.125))
    return np.concatenate(pts), np.concatenate(times)


def test_text_is_fixed_in_the_frame_and_moving_arcs_are_not():
    points, times = _clip()
    fixed = fixed_in_frame(points, times)
    text = points[:, 1] > 400
    assert fixed[text].mean() > 0.8
    # an arc that slides along itself keeps a few points on the same pixels: a group of light is
    # left out only when most of it is fixed (next test)
    assert fixed[~text].mean() < 0.2


def test_the_text_is_left_out_whole_with_its_changing_character():
    points, times = _clip()
    weights = np.ones(len(points))
    kept, w, t, band, share = without_fixed_light(points, weights, times, None, 4.0)
    assert np.all(kept[:, 1] < 400), "the changing character goes with the fixed text around it"
    assert len(kept) == int(np.sum(points[:, 1] < 400))
    assert math.isclose(share, float(np.mean(points[:, 1] > 400)))


def test_nothing_is_left_out_when_nothing_is_fixed_or_everything_is():
    points, times = _clip()
    arcs = points[:, 1] < 400
    assert without_fixed_light(points[arcs], np.ones(arcs.sum()), times[arcs], None, 4.0) is None
    # a still camera: the pattern itself stays put, and nothing would be left to fit
    still = points[times == times[0]]
    everything = np.concatenate([still] * CHUNKS)
    stamps = np.repeat(np.unique(times), len(still))
    assert without_fixed_light(everything, np.ones(len(everything)), stamps, None, 4.0) is None


def test_pattern_moved_from_drift_and_wander():
    times = np.repeat(0.25 * np.arange(CHUNKS) + 0.125, 10)
    diag = {"drift_px_s": [4.0, -3.0], "wander_px": None}
    assert math.isclose(pattern_moved_px(diag, times), 5.0 * 0.25 * (CHUNKS - 1))
    offsets = [[0.0, 0.0]] * CHUNKS
    offsets[3] = [0.0, 40.0]
    diag = {"drift_px_s": [0.0, 0.0], "wander_px": {"rms": 1.0, "chunk_offsets": offsets}}
    assert math.isclose(pattern_moved_px(diag, times), 40.0)
