"""A pattern centre that wanders: a camera on a tripod on a bench that shakes, or a rig whose
mean tilt breathes, moves the whole trace by tens of pixels over a clip, not along a straight
line. The fit's linear drift (:mod:`labkit.vision.laser.pattern_fit`) cannot follow that; this module adds one
translation per time chunk on top of it.

Each chunk's trace is moved onto the fitted curve by the translation that best cancels its
residuals along the curve's normals (a linearised registration against the known shape); the
curve is then refitted on the moved points, and the two steps alternate. The translations'
weighted mean and linear trend are handed back to the centre and the drift (they are the same
thing), so the chunk offsets are what a straight drift does not explain. The centre at any time
is the fitted centre, plus the drift, plus the offsets interpolated linearly between the chunks'
mid times. Pure functions, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from labkit.vision.laser.nearest import PointTree, xy_points
from labkit.vision.laser.pattern_fit import (
    SETTLE_PX,
    Classification,
    CurveFit,
    polish,
    polished_on_band,
    without_outliers,
)
from labkit.vision.shared.curves import SIMPLER_TOLERANCE

MIN_CHUNKS = 3
MIN_CHUNK_POINTS = 10


def dense_curve(fit: CurveFit, spacing_px: float = 0.3) -> tuple[np.ndarray, np.ndarray]:
    """Curve points (complex, at the fit's reference time: no drift) about ``spacing_px`` apart
    along the curve, uniform in the parameter t and a multiple of the curve's symmetry
    ``|k - 1|`` in number, and each sample's share of the curve's length."""
    k = fit.k
    t = np.linspace(0.0, 2 * math.pi, 512 * max(2, abs(k)), endpoint=False)
    speed = np.abs(1j * fit.a * np.exp(1j * t) + 1j * k * fit.b * np.exp(1j * k * t))
    length = float(np.mean(speed)) * 2 * math.pi
    m = abs(k - 1)
    n = m * math.ceil(min(200000, max(len(t), length / spacing_px)) / m)
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    e1, ek = np.exp(1j * t), np.exp(1j * k * t)
    speed = np.abs(1j * fit.a * e1 + 1j * k * fit.b * ek)
    return fit.c + fit.a * e1 + fit.b * ek, speed / np.sum(speed)


MIN_CHUNK_COVERAGE = 0.5  # a chunk that shows less of the pattern cannot tell a shift from a shape


def chunk_offsets(fit: CurveFit, still: np.ndarray, chunk: np.ndarray, chunks: int,
                  width: float, search_px: float = 0.0) -> np.ndarray:
    """Per chunk (``chunk``: each point's chunk index), the translation (complex px) that best
    moves its points ``still`` (drift already taken out) onto the curve along the curve's
    normals. A chunk whose light covers less than ``MIN_CHUNK_COVERAGE`` of the curve's length
    (within ``width`` px) gets NaN: on a part of the pattern a shift and a change of shape look
    alike (symmetric copies do not help here: a shift moves opposite sides the same way, a change
    of size opposite ways, and only seeing both tells them apart).

    The normals of the nearest curve points are right only for a chunk already within about a
    line width of the curve. With ``search_px``, a chunk that cannot be registered where it is
    is moved first by the shift within ``search_px`` that brings its light closest to the curve
    (:class:`CoarseShift`), so that a chunk a camera moved by several line widths from where the
    drift puts it is registered too. (Only then: a steady clip costs no search.)"""
    curve, share = dense_curve(fit, 0.5)
    tree = PointTree(curve)
    coarse: CoarseShift | None = None
    offsets = np.full(chunks, np.nan + 0j)
    for j in range(chunks):
        sel = chunk == j
        if sel.sum() < MIN_CHUNK_POINTS:
            continue
        offsets[j] = _registered(still[sel], curve, share, tree, width, 0j)
        if np.isnan(offsets[j]) and search_px > 0:  # too far off for the normals: search first
            coarse = coarse or CoarseShift(curve, width, search_px)
            offsets[j] = _registered(still[sel], curve, share, tree, width, coarse.best(still[sel]))
    return offsets


def _registered(points: np.ndarray, curve: np.ndarray, share: np.ndarray, tree: PointTree, width: float,
                shift: complex) -> complex:
    """The translation of one chunk's ``points`` onto the curve along its normals, starting from
    ``shift`` (only the light within 2 line widths of the curve then measures it); NaN when the
    chunk's light covers too little of the curve or does not fix both directions."""
    pts = points - shift
    dist, idx = tree.query(pts)
    if float(np.sum(share[lit_samples(curve, pts, dist, idx, width)])) < MIN_CHUNK_COVERAGE:
        return complex(np.nan, np.nan)
    residual = pts - curve[idx]
    if shift != 0:
        residual = residual[dist <= 2 * width]
    normal = residual / np.maximum(np.abs(residual), 1e-9)
    nx, ny, d = normal.real, normal.imag, (np.conj(normal) * residual).real
    m = np.array([[nx @ nx, nx @ ny], [nx @ ny, ny @ ny]])
    if len(d) < MIN_CHUNK_POINTS or np.linalg.cond(m) > 1e6:
        return complex(np.nan, np.nan)
    sx, sy = np.linalg.solve(m, np.array([nx @ d, ny @ d]))
    return shift + complex(sx, sy)


def lit_samples(curve: np.ndarray, points: np.ndarray, dist: np.ndarray, idx: np.ndarray,
                width: float) -> np.ndarray:
    """Which samples of the closed ``curve`` have one of ``points`` within ``width`` (``dist``,
    ``idx``: each point's distance to and index of its nearest sample). Exact, and cheaper than
    querying every sample against the points: a sample a few places along the curve from a
    point's nearest one is checked directly (for a chunk that shows the whole pattern these cover
    nearly every sample), and only the samples this leaves dark are searched in a kd-tree of the
    points (with a bound of twice ``width``, which only prunes: distances up to it are exact)."""
    n = len(curve)
    lit = np.zeros(n, bool)
    near = dist <= width  # a point farther from every sample lights none
    count = int(np.count_nonzero(near))
    if count:
        spacing = float(np.mean(np.abs(np.diff(curve))))
        reach = max(1, min(int(width / max(spacing, 1e-9)) + 1, n // (2 * count) + 2))
        window = (idx[near, None] + np.arange(-reach, reach + 1)[None, :]) % n
        lit[window[np.abs(curve[window] - points[near, None]) <= width]] = True
    dark = np.flatnonzero(~lit)
    if len(dark):
        lit[dark] = PointTree(points).query(curve[dark], distance_upper_bound=2 * width)[0] <= width
    return lit


class CoarseShift:
    """The shift within ``search_px`` (on a grid of half a line width, or a tenth of
    ``search_px`` if coarser) that brings a chunk's light closest to the curve: least mean
    squared distance to the curve, each distance capped at two line widths (light away from the
    curve, or curve the chunk does not show, then weighs the same at every shift). The
    distances come from a distance transform of the curve drawn on a raster of about 1 px."""

    def __init__(self, curve: np.ndarray, width: float, search_px: float) -> None:
        self.cap = 2.0 * width
        self.step = max(1.0, 0.5 * width, search_px / 10)  # at most 21 x 21 shifts
        pad = search_px + self.cap + 2
        self.cell = max(1.0, float(max(np.ptp(curve.real), np.ptp(curve.imag)) + 2 * pad) / 3000)
        self.origin = complex(curve.real.min() - pad, curve.imag.min() - pad)
        size = (np.array([np.ptp(curve.real), np.ptp(curve.imag)]) + 2 * pad) / self.cell + 2
        mask = np.full((int(size[1]), int(size[0])), 255, np.uint8)
        c = np.round((curve - self.origin) / self.cell)
        mask[c.imag.astype(int), c.real.astype(int)] = 0
        self.distance = cv2.distanceTransform(mask, cv2.DIST_L2, 5) * self.cell
        n = int(search_px // self.step)
        g = np.arange(-n, n + 1) * self.step
        self.shifts = (g[:, None] + 1j * g[None, :]).ravel()

    def best(self, points: np.ndarray, max_points: int = 300) -> complex:
        """The best shift (complex px) of ``points`` (complex)."""
        pts = points[:: max(1, len(points) // max_points)]
        z = (pts[None, :] - self.shifts[:, None] - self.origin) / self.cell
        h, w = self.distance.shape
        x = np.clip(np.round(z.real).astype(int), 0, w - 1)
        y = np.clip(np.round(z.imag).astype(int), 0, h - 1)
        d = np.minimum(self.distance[y, x], self.cap)
        return complex(self.shifts[int(np.argmin(np.mean(d * d, axis=1)))])


# rounds go on until one moves the offsets by less than ``WANDER_SETTLE_PX`` (rms over the chunks),
# and while the chunks registered grow in number: a chunk next to a registered one comes within
# reach once its neighbour's offset is known (a camera moving 52 px across a 1280x720 clip: 4, 6,
# 7, then 8 of 8 chunks). The offsets' change shrinks about 4x per round (the 720p bench clip:
# 0.34, 0.047, 0.012 px): what 0.05 px leaves is ~0.015 px, a thirtieth of the centre's stated
# accuracy (labkit/vision/laser/version.py). ADR 0043.
WANDER_SETTLE_PX = 0.05
MAX_ROUNDS = 8
SEARCH_SHARE = 0.1  # a chunk's coarse shift is searched within this share of the pattern's radius


def search_px(fit: CurveFit, width: float) -> float:
    """How far a chunk's coarse shift is searched: ``SEARCH_SHARE`` of the pattern's largest
    radius (farther, a part of the pattern could be matched to a neighbouring branch), and at
    least 3 line widths."""
    return max(3.0 * width, SEARCH_SHARE * (abs(fit.a) + abs(fit.b)))


def filled(offsets: np.ndarray, mid_times: np.ndarray) -> np.ndarray:
    """NaN offsets interpolated linearly in time from the chunks that have one (0 if none has)."""
    ok = np.isfinite(offsets)
    if not ok.any():
        return np.zeros(len(offsets), complex)
    return (np.interp(mid_times, mid_times[ok], offsets[ok].real)
            + 1j * np.interp(mid_times, mid_times[ok], offsets[ok].imag))


def robust_rms(fit: CurveFit, still: np.ndarray) -> float:
    """Rms distance of points ``still`` (drift taken out) from the curve, leaving out points
    farther than 3 x the median distance (spurs of the centre line, specks)."""
    curve, _ = dense_curve(fit, 0.5)
    d, _ = PointTree(curve).query(still)
    d = d[d <= 3 * max(float(np.median(d)), 1 / 3)]
    return float(np.sqrt(np.mean(d * d))) if len(d) else math.nan


def _detrended(offsets: np.ndarray, mid_times: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Offsets without their count-weighted mean and linear trend in time (the centre's and the
    drift's share)."""
    w = counts.astype(float)
    if w.sum() <= 0:
        return offsets
    design = np.column_stack([np.ones(len(mid_times)), mid_times - np.average(mid_times, weights=w)])
    sw = np.sqrt(w)[:, None]
    coef = np.linalg.lstsq(design * sw, offsets * sw[:, 0], rcond=None)[0]
    return offsets - design @ coef


@dataclass
class Wander:
    """The fit with the wander taken out, the time its centre refers to, and the chunks' mid
    times with their offsets (complex px)."""

    fit: CurveFit
    t_ref: float
    mid_times: np.ndarray
    offsets: np.ndarray
    chunks_checked: int = 0  # chunks that showed enough of the pattern to measure their offset
    rms_straight_px: float = math.nan  # residual of the straight-drift fit on the same points
    rms_followed_px: float = math.nan  # residual with the chunk offsets followed

    @property
    def needed(self) -> bool:
        """Whether following the wander explains the trace clearly better than a straight drift
        (by the factor a trochoid must beat an ellipse by, ``SIMPLER_TOLERANCE``): otherwise the
        chunk offsets fit small shape errors of partial chunks, and the simpler model stays."""
        return bool(self.rms_straight_px > SIMPLER_TOLERANCE * self.rms_followed_px)

    def centre_at(self, t: float) -> complex:
        """The pattern centre at time ``t`` (s)."""
        extra = complex(np.interp(t, self.mid_times, self.offsets.real),
                        np.interp(t, self.mid_times, self.offsets.imag))
        return self.fit.c + self.fit.drift * (t - self.t_ref) + extra

    def moved(self, points: np.ndarray, times: np.ndarray) -> np.ndarray:
        """``points`` (N, 2) with their chunk's offset taken out (``times``: the chunks' mid times)."""
        chunk = np.clip(np.searchsorted(self.mid_times, times), 0, len(self.offsets) - 1)
        off = self.offsets[chunk]
        return points - np.column_stack([off.real, off.imag])

    @property
    def rms_px(self) -> float:
        return float(np.sqrt(np.mean(np.abs(self.offsets) ** 2))) if len(self.offsets) else 0.0


def follow_wander(cls: Classification, points: np.ndarray, weights: np.ndarray | None, times: np.ndarray,
                  width: float, band: tuple | None = None, settle_px: float = WANDER_SETTLE_PX,
                  max_points: int = 3000) -> Wander | None:
    """Alternate chunk offsets and a refit of ``cls.best`` (see the module docstring) until a round
    moves the offsets by less than ``settle_px`` (rms) and registers no more chunks than the one
    before (at most ``MAX_ROUNDS``); None for fewer than ``MIN_CHUNKS`` chunks. An ellipse whose
    wander is :attr:`Wander.needed` is polished at the end on every trace pixel ``band`` (points,
    weights, times), moved by the offsets, as
    :func:`labkit.vision.laser.pattern_fit.classify` does (a thinned centre line ends short of a flat
    ellipse's tips). A wander that is not needed keeps the straight-drift fit in the analysis
    (:func:`labkit.vision.laser.pattern._steadied`), so its fit is not polished: that polish is a third of
    the work after the last frame of a steady clip and would be thrown away (the decision,
    :attr:`Wander.needed`, and the offsets do not depend on it)."""
    mid_times, chunk = np.unique(np.asarray(times, float), return_inverse=True)
    if len(mid_times) < MIN_CHUNKS:
        return None
    keep = np.random.default_rng(4).permutation(len(points))[:max_points]
    z = points[keep, 0] + 1j * points[keep, 1]
    w = None if weights is None else np.asarray(weights, float)[keep]
    t, ch = np.asarray(times, float)[keep], chunk[keep]
    counts = np.bincount(ch, minlength=len(mid_times))
    t_ref = float(np.mean(t))
    fit = replace(cls.best, c=cls.best.c + cls.best.drift * (t_ref - cls.t_ref))
    rms_straight = robust_rms(fit, z - fit.drift * (t - t_ref))
    total = np.zeros(len(mid_times), complex)
    checked = 0
    for _ in range(MAX_ROUNDS):
        still = z - total[ch] - fit.drift * (t - t_ref)
        raw = chunk_offsets(fit, still, ch, len(mid_times), width, search_px(fit, width))
        before, checked = checked, int(np.isfinite(raw).sum())
        if checked == 0:  # no chunk can be registered: keep the straight drift
            zeros = np.zeros(len(mid_times), complex)
            return Wander(fit, t_ref, mid_times, zeros, 0, rms_straight, rms_straight)
        previous = total
        total = _detrended(total + filled(raw, mid_times), mid_times, counts)
        moved = z - total[ch]
        fit = polish(fit, xy_points(moved), w, t, 8, SETTLE_PX)
        change = float(np.sqrt(np.mean(np.abs(total - previous) ** 2)))
        if change < settle_px and (checked == len(mid_times) or checked <= before):
            break
    if fit.k != -1:
        fit = without_outliers(fit, xy_points(moved), w, t)
    result = Wander(fit, t_ref, mid_times, total, checked, rms_straight,
                    robust_rms(fit, z - total[ch] - fit.drift * (t - t_ref)))
    if (result.needed and fit.k == -1 and band is not None and band[2] is not None
            and len(band[0]) >= MIN_CHUNK_POINTS):
        moved_band = (result.moved(np.asarray(band[0], float), np.asarray(band[2], float)), band[1], band[2])
        result.fit = polished_on_band(fit, moved_band, (xy_points(moved), w, t), 2 * max_points)
    return result
