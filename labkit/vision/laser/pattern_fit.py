"""Fit and classify a trace (an unordered, weighted point cloud) as circle, ellipse, epitrochoid
or hypotrochoid (Sec. 5.2.3 Fig. 5.19/5.20, Sec. 6.5 Eq. 6.38).

All patterns share the model ``z(t) = c + v tau + A e^{it} + B e^{ikt}`` (see
:mod:`labkit.vision.shared.curves`), where ``tau`` is each point's time relative to the middle of the
recording and ``v`` a slow linear drift of the pattern centre. With the curve parameter ``t_i`` of
each point's closest curve point fixed, the model is linear in the complex ``c, v, A, B``; the fit
alternates closest-point search and a weighted linear least-squares solve (iterative closest
point). Pure functions: no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import cv2
import numpy as np

from labkit.vision.laser.icp import FitRows, closest_parameters, icp_rows
from labkit.vision.laser.nearest import PointTree
from labkit.vision.laser.starts import b_starts_for, trochoid_starts
from labkit.vision.shared.curves import (
    CIRCLE_MAX_ELLIPTICITY,
    Pattern,
    a_for_k,
    ellipse_from_coefficients,
    k_for,
    phasors,
    trochoid_beats,
    trochoid_from_coefficients,
)

MIN_POINTS = 20
# a prior classification (of part of the trace) is trusted while its choice explains the whole
# trace nearly as well as it explained the part: rms <= PRIOR_RMS_FACTOR x its rms + PRIOR_RMS_SLACK_PX
PRIOR_RMS_FACTOR = 1.5
PRIOR_RMS_SLACK_PX = 0.5
# a refit from a fit already close to its points (the wander's rounds, the band polish) stops at
# the first step in which the curve moved by less than this (px):
# docs/decisions/0039-laser-refits-stop-when-settled.md
SETTLE_PX = 1e-3


@dataclass
class CurveFit:
    """One fitted model: complex coefficients, drift (px/s), residual and the canonical pattern."""

    k: int
    c: complex
    a: complex
    b: complex
    drift: complex
    rms_residual: float
    pattern: Pattern


@dataclass
class Classification:
    """The chosen fit, the ellipse fit (always reported: semi-axes, ellipticity) and all candidates'
    residuals keyed ``"ellipse"``, ``"epitrochoid-3"``..."""

    best: CurveFit
    ellipse: CurveFit
    residuals: dict[str, float] = field(default_factory=dict)
    t_ref: float = 0.0  # the time the centres refer to (mean time of the points fitted)
    coverage: dict[str, float] = field(default_factory=dict)  # trochoids' coverage_rms, same keys
    fits: dict[str, CurveFit] = field(default_factory=dict)  # every trochoid candidate's fit, same keys


def _curve(c: complex, a: complex, b: complex, k: int, t: np.ndarray) -> np.ndarray:
    e1, ek = phasors(t, k)
    return c + a * e1 + b * ek


PROBE_ITERATIONS = 4  # every start gets this many steps; only the best one is carried on


def _curve_fit(rows: FitRows, rms: np.ndarray, i: int) -> CurveFit:
    """Row ``i`` as a :class:`CurveFit` with its canonical pattern."""
    k, c, a, b = int(rows.k[i]), complex(rows.c[i]), complex(rows.a[i]), complex(rows.b[i])
    pattern = ellipse_from_coefficients(c, a, b) if k == -1 else trochoid_from_coefficients(c, a, b, k)
    return CurveFit(k, c, a, b, complex(rows.v[i]), float(rms[i]), pattern)


def _icp(z: np.ndarray, w: np.ndarray, tau: np.ndarray, k: int, c: complex, a: complex, b: complex,
         iterations: int, fit_drift: bool, samples: int, v: complex = 0j,
         settle_px: float | None = None) -> CurveFit:
    """ICP of one curve (:func:`labkit.vision.laser.icp.icp_rows` with one row)."""
    rows = FitRows(np.array([k]), np.array([c], complex), np.array([a], complex), np.array([b], complex),
                 np.array([v], complex))
    return _curve_fit(*icp_rows(z, w, tau, rows, iterations, fit_drift, np.array([samples]), settle_px), 0)


def _ellipse_start(z: np.ndarray) -> tuple[complex, complex, complex]:
    pts = np.column_stack([z.real, z.imag]).astype(np.float32)
    (cx, cy), (w_, h_), ang = cv2.fitEllipseAMS(pts)
    if not all(map(math.isfinite, (cx, cy, w_, h_, ang))) or max(w_, h_) <= 0:
        (cx, cy), (w_, h_), ang = cv2.fitEllipse(pts)
    # OpenCV: full axes (w, h), w along angle; normalise to major first
    major, minor, rot = w_ / 2, h_ / 2, math.radians(ang)
    if minor > major:
        major, minor, rot = minor, major, rot + math.pi / 2
    e = complex(math.cos(rot), math.sin(rot))
    return complex(cx, cy), e * (major + minor) / 2, e * (major - minor) / 2


def fit_ellipse(points: np.ndarray, weights: np.ndarray | None = None, times: np.ndarray | None = None,
                iterations: int = 18) -> CurveFit:
    """Geometric ellipse fit (major first; rotation of the major axis) with optional linear drift."""
    z, w, tau = prepare_points(points, weights, times)
    c, a, b = _ellipse_start(z)
    return _icp(z, w, tau, -1, c, a, b, iterations, times is not None, 1440)


def fit_trochoid(points: np.ndarray, kind: str, loops: int, weights: np.ndarray | None = None,
                 times: np.ndarray | None = None, iterations: int = 30,
                 b_starts: tuple[float, ...] | None = None) -> CurveFit:
    """Fit an epitrochoid or hypotrochoid (Eq. 6.38) with ``loops`` loops: a few steps from each
    start (:func:`labkit.vision.laser.starts.trochoid_starts`), then the best one to ``iterations`` steps."""
    return fit_trochoids(points, [k_for(kind, loops)], weights, times, iterations, b_starts)[0]


def fit_trochoids(points: np.ndarray, ks: list[int], weights: np.ndarray | None = None,
                  times: np.ndarray | None = None, iterations: int = 30,
                  b_starts: tuple[float, ...] | None = None) -> list[CurveFit]:
    """:func:`fit_trochoid` for several frequency ratios ``ks`` (:func:`labkit.vision.shared.curves.k_for`)
    at once, one fit per k: every start of every k is probed for ``PROBE_ITERATIONS`` steps in one
    batch, then each k's best start is carried on to ``iterations`` steps in a second batch."""
    z, w, tau = prepare_points(points, weights, times)
    drift = times is not None
    starts = [(k, c, a, b) for k in ks
              for c, a, b in trochoid_starts(z, w, k, b_starts or b_starts_for(k))]
    k_col, c, a, b = (np.array(col) for col in zip(*starts, strict=True))
    probes = FitRows(k_col, c, a, b, np.zeros(len(starts), complex))
    probes, rms = icp_rows(z, w, tau, probes, PROBE_ITERATIONS, drift, 200 * np.abs(k_col))
    chosen = []
    for k in ks:
        mine = np.flatnonzero(k_col == k)
        finite = mine[np.isfinite(rms[mine])]
        if len(finite):
            # ranked as candidates are (two_way_rms): a start that grew loops larger than the
            # trace's passes close to every point and would win on the residual alone
            scores = [two_way_rms(rms[i], coverage_rms(_curve_fit(probes, rms, i), z, tau)) for i in finite]
            chosen.append(finite[int(np.argmin(scores))])
        else:  # every start degenerated; keep the least bad
            chosen.append(mine[np.argmin(np.abs(probes.b[mine]) / np.maximum(np.abs(probes.a[mine]), 1e-12))])
    best = probes.take(chosen)
    rows, rms = icp_rows(z, w, tau, best, max(0, iterations - PROBE_ITERATIONS), drift, 200 * np.abs(best.k))
    return [_curve_fit(rows, rms, i) for i in range(len(ks))]


def prepare_points(points, weights, times):
    """Points (N, 2) as complex numbers, their weights and centred times; ValueError on a bad shape."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < MIN_POINTS:
        raise ValueError(f"need at least {MIN_POINTS} points (N, 2), got shape {pts.shape}")
    z = pts[:, 0] + 1j * pts[:, 1]
    w = np.ones(len(z)) if weights is None else np.asarray(weights, dtype=float)
    tau = np.zeros(len(z)) if times is None else np.asarray(times, dtype=float) - np.mean(times)
    return z, w, tau


def _mean_time(times: np.ndarray | None) -> float:
    return float(np.mean(times)) if times is not None else 0.0


def _subsample(n: int, keep: int, seed: int = 0) -> np.ndarray:
    if n <= keep:
        return np.arange(n)
    return np.sort(np.random.default_rng(seed).choice(n, keep, replace=False))


def classify(points: np.ndarray, weights: np.ndarray | None = None, times: np.ndarray | None = None,
             max_points: int = 1200, screen_points: int = 250,
             trochoid_loops: range = range(2, 8),
             band: tuple[np.ndarray, np.ndarray | None, np.ndarray | None] | None = None,
             prior: Classification | None = None) -> Classification:
    """Fit every candidate (ellipse, epitrochoids with 2-7 loops, hypotrochoids with 3-7 loops) on a
    subsample, refine the two best on up to ``max_points`` points, and pick the simplest pattern
    that explains the trace (a trochoid must beat the ellipse's residual by ``SIMPLER_TOLERANCE``).
    Trochoids are ranked against each other by :func:`two_way_rms`, which adds how well the light
    covers the curve: on thick, haloed traces a trochoid with more and larger loops than the
    pattern can pass as close to the light as the right one (hard 720p footage: a 4-loop
    epitrochoid read as 7 loops with b = 0.85, 3.1 px residual against 3.5 px, but 47 px of
    coverage against 6 px).
    ``band`` (points, weights, times): every trace pixel; an ellipse that wins is polished on it,
    because a thinned centre line ends half a line width short of the sharp tips of a flat ellipse.
    ``prior``: a classification of part of the same trace (e.g. the first half of a video, done
    while the rest was decoding); its choice is kept and only refined, with no new screening,
    unless the refined choice fits the whole trace much worse than it fitted the part (a part that
    showed too little of the pattern, e.g. few frames at a large stride): then every candidate
    is screened again."""
    pts = np.asarray(points, dtype=float)
    w = None if weights is None else np.asarray(weights, dtype=float)
    tm = None if times is None else np.asarray(times, dtype=float)

    def take(idx):
        return pts[idx], (None if w is None else w[idx]), (None if tm is None else tm[idx])

    full = take(_subsample(len(pts), max_points))
    screen = take(_subsample(len(pts), screen_points, seed=1))
    ellipse = fit_ellipse(*full)
    t_ref = _mean_time(full[2])
    residuals = {"ellipse": ellipse.rms_residual}
    coverage: dict[str, float] = {}
    fits: dict[str, CurveFit] = {}
    if prior is not None:
        residuals.update({f"{k} (first part)": v for k, v in prior.residuals.items()})
        f = prior.best
        shortlist = [] if f.k == -1 else [replace(f, c=f.c + f.drift * (t_ref - prior.t_ref))]
    else:
        ks = [k_for(kind, loops) for kind, first in (("epitrochoid", 2), ("hypotrochoid", 3))
              for loops in trochoid_loops if loops >= first]
        zs, _, taus = prepare_points(*screen)
        screened = fit_trochoids(screen[0], ks, screen[1], screen[2], iterations=10)
        for f in screened:
            residuals[_name(f)], fits[_name(f)] = f.rms_residual, f
            coverage[_name(f)] = coverage_rms(f, zs, taus) if math.isfinite(f.rms_residual) else math.inf
        screened.sort(key=lambda f: two_way_rms(f.rms_residual, coverage[_name(f)]))
        shortlist = [f for f in screened[:2] if math.isfinite(f.rms_residual)]
    z, w_, tau = prepare_points(*full)
    refined = []
    if shortlist:  # refined together: one batch of ICP steps for both
        rows = FitRows.of(shortlist)
        rows, rms = icp_rows(z, w_, tau, rows, 20, full[2] is not None, 200 * np.abs(rows.k))
        refined = [_curve_fit(rows, rms, i) for i in range(len(shortlist))]
    for fit in refined:
        residuals[_name(fit)], coverage[_name(fit)] = fit.rms_residual, coverage_rms(fit, z, tau)
        fits[_name(fit)] = fit
    trochoid = min(refined, key=lambda f: two_way_rms(f.rms_residual, coverage[_name(f)]), default=None)

    def trochoid_wins() -> bool:
        return trochoid is not None and trochoid_beats(trochoid.rms_residual, abs(trochoid.b),
                                                       ellipse.rms_residual)

    beats = trochoid_wins()
    if not beats and band is not None and len(band[0]) >= MIN_POINTS:
        # the ellipse looks like the answer: polish it on the band and judge again (polishing
        # only raises its residual on the centre line, so a trochoid that beat the unpolished
        # ellipse would beat the polished one too: that work is skipped for trochoids)
        ellipse = polished_on_band(ellipse, band, full, 2 * max_points)
        residuals["ellipse"] = ellipse.rms_residual
        beats = trochoid_wins()
    best = without_outliers(trochoid, *full) if beats and trochoid is not None else ellipse  # beats: one
    if prior is not None and not (
            best.rms_residual <= PRIOR_RMS_FACTOR * prior.best.rms_residual + PRIOR_RMS_SLACK_PX):
        return classify(points, weights, times, max_points, screen_points, trochoid_loops, band)
    return Classification(best, ellipse, residuals, t_ref, coverage, fits)


def polished_on_band(ellipse: CurveFit, band: tuple, full: tuple, max_points: int) -> CurveFit:
    """The ellipse refitted on (up to ``max_points`` of) every trace pixel ``band`` without its
    outliers, with its residual taken on the centre-line points ``full`` (comparable with the
    trochoids'). Centres refer to the mean time of the points fitted, so the band fit's centre is
    moved to the centre line's."""
    idx = _subsample(len(band[0]), max_points, seed=2)
    subset: list[Any] = [None if a is None else np.asarray(a)[idx] for a in band]  # times may be None
    # started from the ellipse's drift, its centre moved to the subset's mean time (the band is the
    # same light as the centre line: the refit only settles; see SETTLE_PX)
    pts, wts, tms = subset
    start = replace(ellipse, c=ellipse.c + ellipse.drift * (_mean_time(tms) - _mean_time(full[2])))
    polished = without_outliers(polish(start, pts, wts, tms, 12, SETTLE_PX), pts, wts, tms,
                                settle_px=SETTLE_PX)
    shift = polished.drift * (_mean_time(full[2]) - _mean_time(subset[2]))
    z, w, tau = prepare_points(*full)
    return _icp(z, w, tau, -1, polished.c + shift, polished.a, polished.b, 0, False, 1440, polished.drift)


OUTLIER_SIGMAS = 3.0  # a last refit leaves out points this many robust sigmas off the curve


def without_outliers(fit: CurveFit, points: np.ndarray, weights: np.ndarray | None = None,
                     times: np.ndarray | None = None, iterations: int = 12,
                     settle_px: float | None = None) -> CurveFit:
    """Refit ``fit`` without the points farther from it than ``OUTLIER_SIGMAS`` robust sigmas
    (sigma = 1.4826 x the median distance, at least 1/3 px): specks of compression ringing or
    halo beside a bright trace, a few % of the points but tens of px off, would otherwise pull
    the centre and b. The rms residual of the result is over the points kept; ``settle_px`` as
    in :func:`polish`."""
    z, w, tau = prepare_points(points, weights, times)
    rows = FitRows.of([fit])
    samples = np.array([1440 if fit.k == -1 else 200 * abs(fit.k)])
    t = closest_parameters((z - fit.c - fit.drift * tau)[None, :], rows, samples)[0]
    distance = np.abs(_curve(fit.c, fit.a, fit.b, fit.k, t) + fit.drift * tau - z)
    keep = distance <= OUTLIER_SIGMAS * max(1.4826 * float(np.median(distance)), 1 / 3)
    if keep.all() or keep.sum() < MIN_POINTS:
        return fit
    return _icp(z[keep], w[keep], tau[keep], fit.k, fit.c, fit.a, fit.b, iterations, times is not None,
                int(samples[0]), fit.drift, settle_px)


def two_way_rms(residual: float, coverage: float) -> float:
    """Mean-square of the trace-to-curve residual and the curve-to-trace :func:`coverage_rms`:
    the score that ranks trochoids against each other (a curve must explain the light and the
    light must cover the curve)."""
    return math.sqrt(0.5 * (residual * residual + coverage * coverage))


def coverage_rms(fit: CurveFit, z: np.ndarray, tau: np.ndarray, samples_per_loop: int = 200) -> float:
    """How well the trace covers the fitted curve: rms distance from the curve (sampled densely,
    each sample weighted by the curve's speed, i.e. uniformly in arc length) to the nearest trace
    point, with the fitted drift taken out. The fit's own residual runs the other way (points to
    curve) and cannot see curve where there is no light: a trochoid with more and larger loops
    than the trace passes near every point and leaves long stretches of dark screen between
    them, which this measure does see."""
    k = fit.k
    t = np.linspace(0.0, 2 * math.pi, samples_per_loop * max(2, abs(k)), endpoint=False)
    e1, ek = phasors(t, k)
    curve = fit.c + fit.a * e1 + fit.b * ek
    speed = np.abs(1j * fit.a * e1 + 1j * k * fit.b * ek)
    still = z - fit.drift * tau
    distance, _ = PointTree(still).query(curve)
    return float(np.sqrt(np.sum(speed * distance**2) / np.sum(speed)))


def polish(fit: CurveFit, points: np.ndarray, weights: np.ndarray | None = None,
           times: np.ndarray | None = None, iterations: int = 12, settle_px: float | None = None) -> CurveFit:
    """Refit from ``fit`` on a different point set (e.g. every trace pixel instead of the thinned
    centre line, which ends half a line width short of sharp tips), ``iterations`` steps from zero
    drift. With ``settle_px`` (a fit whose points moved a little: the wander's rounds, the band
    polish) it starts from the fit's own drift (``times`` centred on the time ``fit`` refers to) and
    stops at the first step in which ``c, A, B`` moved by less than ``settle_px`` in all;
    ``iterations`` then only bounds a fit that does not settle."""
    z, w, tau = prepare_points(points, weights, times)
    samples = 1440 if fit.k == -1 else 360 * abs(fit.k)
    drift = fit.drift if settle_px is not None and times is not None else 0j
    return _icp(z, w, tau, fit.k, fit.c, fit.a, fit.b, iterations, times is not None, samples, drift,
                settle_px)


def _name(fit: CurveFit) -> str:
    return f"{fit.pattern.kind}-{fit.pattern.loops}"


def pattern_kind(fit: CurveFit) -> str:
    """``circle`` for an ellipse with ellipticity below ``CIRCLE_MAX_ELLIPTICITY``, else the kind."""
    p = fit.pattern
    if p.kind == "ellipse":
        major, minor = p.semi_axes
        if major > 0 and 1 - minor / major < CIRCLE_MAX_ELLIPTICITY:
            return "circle"
    return p.kind


def trochoid_a(fit: CurveFit) -> float:
    """Parameter a of Eq. 6.38 for a fitted trochoid."""
    return a_for_k(fit.k)
