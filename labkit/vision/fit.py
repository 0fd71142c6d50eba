"""Fit and classify a trace (an unordered, weighted point cloud) as circle, ellipse, epitrochoid
or hypotrochoid (Sec. 5.2.3 Fig. 5.19/5.20, Sec. 6.5 Eq. 6.38).

All patterns share the model ``z(t) = c + v tau + A e^{it} + B e^{ikt}`` (see
:mod:`labkit.vision.curves`), where ``tau`` is each point's time relative to the middle of the
recording and ``v`` a slow linear drift of the pattern centre. With the curve parameter ``t_i`` of
each point's closest curve point fixed, the model is linear in the complex ``c, v, A, B``; the fit
alternates closest-point search and a weighted linear least-squares solve (iterative closest
point). Pure functions: no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import cv2
import numpy as np
from scipy.spatial import cKDTree

from labkit.vision.curves import (
    Pattern,
    a_for_k,
    ellipse_from_coefficients,
    k_for,
    trochoid_from_coefficients,
)

CIRCLE_MAX_ELLIPTICITY = 0.02  # below this an ellipse is reported as a circle
SIMPLER_TOLERANCE = 1.12  # a simpler pattern wins unless a trochoid's residual is this much lower
MIN_GAIN_PX = 0.1  # ... and at least this much lower in absolute terms
MIN_SECOND_TERM_PX = 1.0  # ... and its second term (b * scale) is visible
MIN_POINTS = 20
MAX_TROCHOID_B = 1.05  # larger b means the fast term dominates: not a trochoid of Eq. 6.38
# a prior classification (of part of the trace) is trusted while its choice explains the whole
# trace nearly as well as it explained the part: rms <= PRIOR_RMS_FACTOR x its rms + PRIOR_RMS_SLACK_PX
PRIOR_RMS_FACTOR = 1.5
PRIOR_RMS_SLACK_PX = 0.5


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


def _curve(c: complex, a: complex, b: complex, k: int, t: np.ndarray) -> np.ndarray:
    return c + a * np.exp(1j * t) + b * np.exp(1j * k * t)


def _closest_parameters(z: np.ndarray, a: complex, b: complex, k: int, samples: int) -> np.ndarray:
    """Parameter t of the closest point of the centred curve ``A e^{it} + B e^{ikt}`` to each z:
    nearest of ``samples`` curve points, then two Newton steps on ``|z(t) - p|^2``."""
    ts = np.linspace(0.0, 2 * math.pi, samples, endpoint=False)
    curve = _curve(0j, a, b, k, ts)
    tree = cKDTree(np.column_stack([curve.real, curve.imag]))
    _, idx = tree.query(np.column_stack([z.real, z.imag]))
    return _newton_parameters(z, a, b, k, ts[idx], 2)


def _newton_parameters(z: np.ndarray, a: complex, b: complex, k: int, t: np.ndarray,
                       steps: int) -> np.ndarray:
    """Refine closest-point parameters by Newton steps on ``|A e^{it} + B e^{ikt} - z|^2``."""
    for _ in range(steps):
        e1, ek = np.exp(1j * t), np.exp(1j * k * t)
        d = a * e1 + b * ek - z
        d1 = 1j * (a * e1 + k * b * ek)
        d2 = -(a * e1 + k * k * b * ek)
        g = (np.conj(d) * d1).real
        h = (np.abs(d1) ** 2 + (np.conj(d) * d2).real)
        step = np.where(h > 1e-12, g / np.maximum(h, 1e-12), 0.0)
        t = t - np.clip(step, -0.2, 0.2)
    return t


PROBE_ITERATIONS = 4  # every start gets this many steps; only the best one is carried on
TANGENTIAL_WEIGHT = 0.2  # share of the along-curve residual kept in the solve (stabilises it)


def _solve_point_to_line(z: np.ndarray, sw: np.ndarray, tau: np.ndarray, k: int, a: complex, b: complex,
                         t: np.ndarray, fit_drift: bool) -> np.ndarray:
    """One linear solve for complex ``c, A, B (, v)`` with the curve parameters t fixed, minimising
    the residual along each point's curve normal plus ``TANGENTIAL_WEIGHT`` times the residual
    along the tangent (point-to-line ICP: it converges in a few steps where plain
    point-to-point ICP slides slowly along the curve)."""
    e1, ek = np.exp(1j * t), np.exp(1j * k * t)
    tangent = 1j * (a * e1 + k * b * ek)
    tangent = tangent / np.maximum(np.abs(tangent), 1e-12)
    basis = [np.ones_like(z), e1, ek] + ([tau.astype(complex)] if fit_drift else [])
    rows, rhs = [], []
    for direction, weight in ((1j * tangent, 1.0), (tangent, TANGENTIAL_WEIGHT)):
        # projection of (complex) x onto a unit direction d: Re(conj(d) x)
        proj = np.conj(direction)
        cols = []
        for g in basis:  # unknown u = ur + i ui contributes Re(proj g) ur - Im(proj g) ui
            pg = proj * g
            cols += [pg.real, -pg.imag]
        rows.append(np.column_stack(cols) * (sw * weight)[:, None])
        rhs.append((proj * z).real * sw * weight)
    m, y = np.vstack(rows), np.concatenate(rhs)
    try:
        x = np.linalg.solve(m.T @ m, m.T @ y)
    except np.linalg.LinAlgError:
        x, *_ = np.linalg.lstsq(m, y, rcond=None)
    return x[0::2] + 1j * x[1::2]


def _icp(z: np.ndarray, w: np.ndarray, tau: np.ndarray, k: int, c: complex, a: complex, b: complex,
         iterations: int, fit_drift: bool, samples: int, v: complex = 0j) -> CurveFit:
    sw = np.sqrt(w)
    t = None
    for it in range(iterations):
        if it % 6 == 0:
            t = _closest_parameters(z - c - v * tau, a, b, k, samples)
        else:
            t = _newton_parameters(z - c - v * tau, a, b, k, t, 2)
        sol = _solve_point_to_line(z, sw, tau, k, a, b, t, fit_drift)
        new = (sol[0], sol[1], sol[2], sol[3] if fit_drift else 0j)
        if k != -1 and abs(new[2]) > MAX_TROCHOID_B * abs(new[1]):  # stay in the trochoid family
            new = (new[0], new[1], new[2] * MAX_TROCHOID_B * abs(new[1]) / abs(new[2]), new[3])
        moved = abs(new[0] - c) + abs(new[1] - a) + abs(new[2] - b)
        c, a, b, v = new
        if moved < 1e-3 and it % 6 == 5:
            break
    if t is None or iterations < 3:
        t = _closest_parameters(z - c - v * tau, a, b, k, samples)
    else:  # warm: the last parameters are close, a Newton refinement is enough
        t = _newton_parameters(z - c - v * tau, a, b, k, t, 2)
    r = np.abs(_curve(c, a, b, k, t) + v * tau - z)
    rms = float(np.sqrt(np.sum(w * r * r) / np.sum(w)))
    if k != -1 and not abs(b) < 0.999 * MAX_TROCHOID_B * abs(a):
        rms = math.inf  # degenerate: the second term dominates (a circle traced |k| times)
    if k == -1:
        pattern = ellipse_from_coefficients(c, a, b)
    else:
        pattern = trochoid_from_coefficients(c, a, b, k)
    return CurveFit(k, c, a, b, v, rms, pattern)


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


def _arc_uniform_canonical(b: float, k: int, n: int = 4096) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    zc = _curve(0j, 1.0, b, k, t)
    speed = np.abs(1j * np.exp(1j * t) + 1j * k * b * np.exp(1j * k * t))
    return zc, speed


def _trochoid_starts(z: np.ndarray, w: np.ndarray, k: int, bs: tuple[float, ...]):
    """Starting coefficients for a trochoid: match the point cloud's centroid, rms radius and the
    phase of its m-fold angular moment (m = |k - 1|, the curve's rotational symmetry) to those of
    the canonical curve sampled uniformly in arc length."""
    cen = complex(np.sum(w * z) / np.sum(w))
    d = z - cen
    rms = math.sqrt(float(np.sum(w * np.abs(d) ** 2) / np.sum(w)))
    m = abs(k - 1)
    power = 2 if m == 1 else 1  # with r^1 the m = 1 moment vanishes at the centroid
    mom = np.sum(w * np.abs(d) ** power * np.exp(-1j * m * np.angle(d)))
    for b in bs:
        zc, speed = _arc_uniform_canonical(b, k)
        cen_c = complex(np.sum(speed * zc) / np.sum(speed))
        dc = zc - cen_c
        rms_c = math.sqrt(float(np.sum(speed * np.abs(dc) ** 2) / np.sum(speed)))
        mom_c = np.sum(speed * np.abs(dc) ** power * np.exp(-1j * m * np.angle(dc)))
        s = rms / rms_c
        rho = (np.angle(mom_c) - np.angle(mom)) / m if abs(mom) > 0 else 0.0
        # a limacon (m = 1) has no symmetry to lock on to: try four quadrants; otherwise the
        # moment's phase and half a symmetry step from it (noise can flip the moment's sign)
        for extra in ((0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi) if m == 1 else (0.0, math.pi / m)):
            e = complex(math.cos(rho + extra), math.sin(rho + extra))
            yield cen - s * e * cen_c, s * e, s * b * e


def fit_ellipse(points: np.ndarray, weights: np.ndarray | None = None, times: np.ndarray | None = None,
                iterations: int = 18) -> CurveFit:
    """Geometric ellipse fit (major first; rotation of the major axis) with optional linear drift."""
    z, w, tau = _prepare(points, weights, times)
    c, a, b = _ellipse_start(z)
    return _icp(z, w, tau, -1, c, a, b, iterations, times is not None, 1440)


def fit_trochoid(points: np.ndarray, kind: str, loops: int, weights: np.ndarray | None = None,
                 times: np.ndarray | None = None, iterations: int = 30,
                 b_starts: tuple[float, ...] = (0.15, 0.45, 0.9)) -> CurveFit:
    """Fit an epitrochoid or hypotrochoid (Eq. 6.38) with ``loops`` loops: a few steps from each
    start (:func:`_trochoid_starts`), then the best one to ``iterations`` steps."""
    z, w, tau = _prepare(points, weights, times)
    k = k_for(kind, loops)
    samples = 200 * abs(k)
    drift = times is not None
    probes = [_icp(z, w, tau, k, c, a, b, PROBE_ITERATIONS, drift, samples)
              for c, a, b in _trochoid_starts(z, w, k, b_starts)]
    best = min(probes, key=lambda f: f.rms_residual)
    if not math.isfinite(best.rms_residual):  # every start degenerated; keep the least bad
        best = min(probes, key=lambda f: abs(f.b) / max(abs(f.a), 1e-12))
    return _icp(z, w, tau, k, best.c, best.a, best.b, max(0, iterations - PROBE_ITERATIONS), drift, samples,
                best.drift)


def _prepare(points, weights, times):
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < MIN_POINTS:
        raise ValueError(f"need at least {MIN_POINTS} points (N, 2), got shape {pts.shape}")
    z = pts[:, 0] + 1j * pts[:, 1]
    w = np.ones(len(z)) if weights is None else np.asarray(weights, dtype=float)
    tau = np.zeros(len(z)) if times is None else np.asarray(times, dtype=float) - np.mean(times)
    return z, w, tau


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
    ``band`` (points, weights, times): every trace pixel; the ellipse is polished on it, because a
    thinned centre line ends half a line width short of the sharp tips of a flat ellipse.
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
    if band is not None and len(band[0]) >= MIN_POINTS:
        idx = _subsample(len(band[0]), 2 * max_points, seed=2)
        polished = polish(ellipse, *(None if a is None else np.asarray(a)[idx] for a in band))
        # its residual on the centre line, comparable with the trochoids'
        z, w_, tau = _prepare(*full)
        ellipse = _icp(z, w_, tau, -1, polished.c, polished.a, polished.b, 0, False, 1440, polished.drift)
    t_ref = float(np.mean(full[2])) if full[2] is not None else 0.0
    residuals = {"ellipse": ellipse.rms_residual}
    if prior is not None:
        residuals.update({f"{k} (first part)": v for k, v in prior.residuals.items()})
        f = prior.best
        shortlist = [] if f.k == -1 else [replace(f, c=f.c + f.drift * (t_ref - prior.t_ref))]
    else:
        screened: list[CurveFit] = []
        for kind, first in (("epitrochoid", 2), ("hypotrochoid", 3)):
            for loops in trochoid_loops:
                if loops < first:
                    continue
                screened.append(fit_trochoid(screen[0], kind, loops, screen[1], screen[2], iterations=10))
        screened.sort(key=lambda f: f.rms_residual)
        for f in screened:
            residuals[_name(f)] = f.rms_residual
        shortlist = [f for f in screened[:2] if math.isfinite(f.rms_residual)]
    best = ellipse
    z, w_, tau = _prepare(*full)
    for f in shortlist:
        fit = _icp(z, w_, tau, f.k, f.c, f.a, f.b, 20, full[2] is not None, 200 * abs(f.k), f.drift)
        residuals[_name(fit)] = fit.rms_residual
        if trochoid_beats(fit.rms_residual, abs(fit.b), best.rms_residual):
            best = fit
    if prior is not None and not (
            best.rms_residual <= PRIOR_RMS_FACTOR * prior.best.rms_residual + PRIOR_RMS_SLACK_PX):
        return classify(points, weights, times, max_points, screen_points, trochoid_loops, band)
    return Classification(best, ellipse, residuals, t_ref)


def polish(fit: CurveFit, points: np.ndarray, weights: np.ndarray | None = None,
           times: np.ndarray | None = None, iterations: int = 12) -> CurveFit:
    """Refit from ``fit`` on a different point set (e.g. every trace pixel instead of the thinned
    centre line, which ends half a line width short of sharp tips)."""
    z, w, tau = _prepare(points, weights, times)
    samples = 1440 if fit.k == -1 else 360 * abs(fit.k)
    return _icp(z, w, tau, fit.k, fit.c, fit.a, fit.b, iterations, times is not None, samples)


def trochoid_beats(trochoid_rms: float, second_term_px: float, simpler_rms: float) -> bool:
    """A trochoid replaces a simpler pattern only if it lowers the residual by the factor
    ``SIMPLER_TOLERANCE`` and by ``MIN_GAIN_PX``, and its second term (``|B| = b * scale``) is at
    least ``MIN_SECOND_TERM_PX``: otherwise it is a circle with invisible wiggles fitted to noise."""
    return (trochoid_rms * SIMPLER_TOLERANCE < simpler_rms and simpler_rms - trochoid_rms > MIN_GAIN_PX
            and second_term_px >= MIN_SECOND_TERM_PX)


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
