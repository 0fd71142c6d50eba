"""Starting values for trochoid fits (Eq. 6.38): pure functions of the point cloud and the
frequency ratio k (:mod:`labkit.vision.shared.curves`)."""

from __future__ import annotations

import functools
import math

import numpy as np


@functools.lru_cache(maxsize=256)
def _canonical_moments(b: float, k: int, n: int = 4096) -> tuple[complex, float, complex]:
    """Centroid, rms radius and m-fold angular moment (see :func:`trochoid_starts`) of the
    canonical trochoid ``e^{it} + b e^{ikt}`` sampled uniformly in arc length; they depend only
    on ``b`` and ``k``, so every trace reuses them."""
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    zc = np.exp(1j * t) + b * np.exp(1j * k * t)
    speed = np.abs(1j * np.exp(1j * t) + 1j * k * b * np.exp(1j * k * t))
    m = abs(k - 1)
    cen_c = complex(np.sum(speed * zc) / np.sum(speed))
    dc = zc - cen_c
    rms_c = math.sqrt(float(np.sum(speed * np.abs(dc) ** 2) / np.sum(speed)))
    mom_c = complex(np.sum(speed * np.abs(dc) ** _moment_power(m) * np.exp(-1j * m * np.angle(dc))))
    return cen_c, rms_c, mom_c


def _moment_power(m: int) -> int:
    return 2 if m == 1 else 1  # with r^1 the m = 1 moment vanishes at the centroid


def trochoid_starts(z: np.ndarray, w: np.ndarray, k: int, bs: tuple[float, ...]):
    """Starting coefficients for a trochoid: match the point cloud's centroid, rms radius and the
    phase of its m-fold angular moment (m = |k - 1|, the curve's rotational symmetry) to those of
    the canonical curve sampled uniformly in arc length."""
    cen = complex(np.sum(w * z) / np.sum(w))
    d = z - cen
    rms = math.sqrt(float(np.sum(w * np.abs(d) ** 2) / np.sum(w)))
    m = abs(k - 1)
    mom = np.sum(w * np.abs(d) ** _moment_power(m) * np.exp(-1j * m * np.angle(d)))
    for b in bs:
        cen_c, rms_c, mom_c = _canonical_moments(float(b), int(k))
        s = rms / rms_c
        rho = (np.angle(mom_c) - np.angle(mom)) / m if abs(mom) > 0 else 0.0
        # a limacon (m = 1) has no symmetry to lock on to: try four quadrants; otherwise the
        # moment's phase and half a symmetry step from it (noise can flip the moment's sign)
        for extra in ((0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi) if m == 1 else (0.0, math.pi / m)):
            e = complex(math.cos(rho + extra), math.sin(rho + extra))
            yield cen - s * e * cen_c, s * e, s * b * e


LOOP_SHAPES = (0.6, 1.4, 2.6)  # |k| b of the starts: no loops, small loops, large loops


def b_starts_for(k: int) -> tuple[float, ...]:
    """Starting values of b for ratio k. The shape of a trochoid is set by ``|k| b`` (the small
    loops form at ``|k| b > 1``, Sec. 6.5), not by b alone: fixed starts in b leave patterns with
    many loops (large |k|) without a start of the right shape. One start per shape of
    ``LOOP_SHAPES``, plus b = 0.9 (a large second term)."""
    bs = {round(min(0.9, s / abs(k)), 3) for s in LOOP_SHAPES} | {0.9}
    return tuple(sorted(bs))
