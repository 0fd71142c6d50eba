"""Light that is not the pattern (labkit.vision.laser.stray_light): a timestamp-like row of strokes close
below a pattern is set apart; arcs of one pattern broken by gaps are all kept."""

from __future__ import annotations

import math

import numpy as np

from labkit.vision.laser.stray_light import separate_pattern


def _circle(centre: complex, radius: float, spacing: float = 0.5,
            arcs: tuple = ((0.0, 2 * math.pi),)) -> np.ndarray:
    pts = []
    for lo, hi in arcs:
        t = np.arange(lo, hi, spacing / radius)
        z = centre + radius * np.exp(1j * t)
        pts.append(np.column_stack([z.real, z.imag]))
    return np.concatenate(pts)


def _text_row(x0: float, y0: float, chars: int, width: float) -> np.ndarray:
    """Strokes like burnt-in characters: short vertical and horizontal bars, 1.2 widths apart."""
    rng = np.random.default_rng(3)
    pts = []
    for i in range(chars):
        x = x0 + i * 1.2 * width
        ys = y0 + np.arange(0, 1.6 * width, 0.5)
        pts.append(np.column_stack([np.full(len(ys), x), ys]))
        if rng.random() < 0.5:
            xs = x + np.arange(0, 0.8 * width, 0.5)
            pts.append(np.column_stack([xs, np.full(len(xs), y0)]))
    return np.concatenate(pts)


def test_timestamp_two_and_a_half_line_widths_below_the_pattern_is_left_out():
    width = 6.0
    ring = _circle(complex(184, 124), 90.0)
    # the row starts left of the circle and ends 2.5 line widths below its lowest point's left
    text = _text_row(10.0, 124 + 90 + 2.5 * width, 20, width)
    sep = separate_pattern(np.concatenate([ring, text]), width)
    assert sep.keep[: len(ring)].all()
    assert not sep.keep[len(ring):].any()
    assert abs(sep.left_out_share - len(text) / (len(ring) + len(text))) < 1e-9
    assert sep.groups >= 1 and sep.rival < 0.5


def test_arcs_of_one_pattern_with_gaps_are_all_kept():
    width = 4.0
    arcs = tuple((a, a + 0.9) for a in np.arange(0, 2 * math.pi, 1.2))  # gaps of 0.3 rad = 30 px
    points = _circle(complex(320, 240), 100.0, arcs=arcs)
    sep = separate_pattern(points, width, np.ones(len(points)))
    assert sep.keep.all() and sep.left_out_share == 0.0


def test_a_reflection_beside_the_pattern_is_left_out_and_a_second_pattern_is_a_rival():
    width = 4.0
    ring = _circle(complex(320, 240), 100.0)
    spot = _circle(complex(320 + 125, 240), 3.0, spacing=0.3)
    other = _circle(complex(600, 240), 90.0)
    sep = separate_pattern(np.concatenate([ring, spot]), width)
    assert sep.keep[: len(ring)].all() and not sep.keep[len(ring):].any() and sep.rival < 0.05
    sep = separate_pattern(np.concatenate([ring, other]), width)
    assert sep.groups == 1 and sep.rival > 0.5
