"""Are a trochoid's small loops seen? (docs/reference/vision-verdicts.md, "Quality verdict", check *loops
seen*.)

A trochoid of Eq. 6.38 forms its small loops when ``|k| b > 1`` (Sec. 6.5). Just past that
point the loops are long and thin: a hypotrochoid with 3 loops and ``b = 0.54`` (``|k| b =
1.08``) has loops 12 % of the scale long but only 2 % wide. Drawn with a line wider than the
loop, the loop is filled in and the trace shows a spike. The spike's shape then fits a curve with
loops of many sizes about as well: b, and the outer extent ``scale (1 + b)`` that the tip of the
loop sets, are not measured. Two pieces of evidence, both in units of the trace:

* :func:`loop_width`: how wide the fitted curve's small loop is (the greatest distance between
  its two branches) in px. A loop narrower than the line has no opening in the light.
* :func:`cusp_fit`: the same pattern refitted with its loops just closed (``b = 1/|k|``, a
  cusp). If that curve explains the light about as well as the fit with loops, the light does
  not tell the two apart, and the difference of their outer extents is how far the extent is
  undetermined.

* :func:`tip_gap`: how far the fitted curve's outer tips lie from the nearest light. A fit that
  grows loops the light does not show pushes its tips beyond the end of the spike, into dark
  screen, while its residual (light to curve) still falls; a right curve's tips lie on the
  light's centre line.

Pure functions, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from labkit.vision.laser.icp import FitRows, closest_parameters, newton_parameters
from labkit.vision.laser.nearest import PointTree
from labkit.vision.laser.pattern_fit import Classification, CurveFit, prepare_points
from labkit.vision.laser.wander import Wander, dense_curve
from labkit.vision.shared.curves import phasors, trochoid_from_coefficients


def loop_width(k: int, b: float, scale: float, samples: int = 4000) -> float:
    """Greatest width (px) of the small loop of ``scale (e^{it} + b e^{ikt})``: 0 without loops.

    The loop is symmetric about the axis through its centre (``t = 0`` for a hypotrochoid, the
    outer tip; ``t = pi / (k - 1)`` for an epitrochoid, the inner side). With ``s`` the parameter
    from there and the axis turned onto the real line, the curve is ``e^{is} + sigma b e^{iks}``
    (``sigma`` +1 for a hypotrochoid, -1 for an epitrochoid); it runs backwards at ``s = 0`` (a
    loop) when ``1 + sigma b k < 0``, and the loop closes where its imaginary part returns to 0."""
    sigma = 1.0 if k < 0 else -1.0
    if 1.0 + sigma * b * k >= 0 or b <= 0:
        return 0.0
    s = np.linspace(0.0, math.pi / abs(k - 1), samples)[1:]
    im = np.sin(s) + sigma * b * np.sin(k * s)
    closed = np.flatnonzero(im >= 0)  # the branch starts negative (running backwards)
    end = int(closed[0]) if len(closed) else len(s)
    return float(2.0 * scale * np.max(-im[:end])) if end > 0 else 0.0


def canonical_phase(fit: CurveFit) -> complex:
    """``A`` of the fit reparametrised so that ``B / A`` is real and positive (``t -> t + tau``
    turns ``A`` by ``tau`` and ``B`` by ``k tau``)."""
    psi = np.angle(fit.b / fit.a) if abs(fit.b) > 0 else 0.0
    return fit.a * complex(np.exp(-1j * psi / (fit.k - 1)))


def cusp_fit(fit: CurveFit, points: np.ndarray, weights: np.ndarray | None = None,
             times: np.ndarray | None = None, iterations: int = 12, b: float | None = None) -> CurveFit:
    """The trochoid ``fit`` refitted on the same points with ``b`` held at ``1/|k|`` (loops just
    closed) or the given value: ``c + A (e^{it} + b e^{ikt}) (+ v tau)`` is linear in ``c, A, v``
    for fixed closest-point parameters, so the fit alternates those as :mod:`labkit.vision.laser.pattern_fit`
    does (point-to-line steps). ``times`` as in the fit (mean-centred drift)."""
    z, w, tau = prepare_points(points, weights, times)
    k = fit.k
    b0 = 1.0 / abs(k) if b is None else float(b)
    a = canonical_phase(fit)
    c, v = fit.c, fit.drift
    sw = np.sqrt(w)
    samples = np.array([200 * abs(k)])
    drift = times is not None
    t: np.ndarray | None = None
    for it in range(iterations):
        rows = FitRows(np.array([k]), np.array([c]), np.array([a]), np.array([b0 * a]), np.array([v]))
        centred = (z - c - v * tau)[None, :]
        if it % 6 == 0 or t is None:  # t is set at iteration 0
            t = closest_parameters(centred, rows, samples)[0:1]
        else:
            t = newton_parameters(centred, rows, t, 2)[0:1]
        c, a, v = _solve_fixed_shape(z, sw, tau, k, b0, a, t[0], drift, v)
    rows = FitRows(np.array([k]), np.array([c]), np.array([a]), np.array([b0 * a]), np.array([v]))
    t = closest_parameters((z - c - v * tau)[None, :], rows, samples)[0]
    r = np.abs(c + a * (np.exp(1j * t) + b0 * np.exp(1j * k * t)) + v * tau - z)
    rms = float(np.sqrt(np.sum(w * r * r) / np.sum(w)))
    return CurveFit(k, c, a, b0 * a, v, rms, trochoid_from_coefficients(c, a, b0 * a, k))


def _solve_fixed_shape(z: np.ndarray, sw: np.ndarray, tau: np.ndarray, k: int, b0: float, a: complex,
                       t: np.ndarray, drift: bool, v: complex) -> tuple[complex, complex, complex]:
    """One weighted least-squares step for ``c, A (, v)`` along each point's curve normal (plus a
    fifth of the tangential residual, as in :func:`labkit.vision.laser.icp.solve_point_to_line`)."""
    e1, ek = phasors(t, k)
    shape = e1 + b0 * ek
    tangent = 1j * a * (e1 + k * b0 * ek)
    tangent = tangent / np.maximum(np.abs(tangent), 1e-12)
    basis = [np.ones_like(shape), shape] + ([tau.astype(complex)] if drift else [])
    blocks, rhs = [], []
    for direction, weight in ((1j * tangent, 1.0), (tangent, 0.2)):
        proj = np.conj(direction)
        cols = []
        for g in basis:
            pg = proj * g
            cols += [pg.real, -pg.imag]
        blocks.append(np.column_stack(cols) * (sw * weight)[:, None])
        rhs.append((proj * z).real * sw * weight)
    x, *_ = np.linalg.lstsq(np.concatenate(blocks), np.concatenate(rhs), rcond=None)
    u = x[0::2] + 1j * x[1::2]
    return complex(u[0]), complex(u[1]), complex(u[2]) if drift else v


def outer_tips(fit: CurveFit) -> np.ndarray:
    """The curve's points farthest from its centre (complex, at the fit's reference time): the
    ``|k - 1|`` outer tips of a trochoid (loop ends of a hypotrochoid, arc tops of an
    epitrochoid), the two ends of an ellipse's major axis."""
    curve, _ = dense_curve(fit, 0.5)
    radius = np.abs(curve - fit.c)
    peaks = np.flatnonzero((radius >= np.roll(radius, 1)) & (radius >= np.roll(radius, -1)))
    count = 2 if fit.k == -1 else abs(fit.k - 1)
    return curve[peaks[np.argsort(-radius[peaks])][:count]]


def tip_gap(fit: CurveFit, still: np.ndarray) -> float:
    """Median over the outer tips (:func:`outer_tips`) of the distance (px) from the tip to the
    nearest trace point ``still`` (complex, drift taken out). The median: a clip that shows only
    part of the pattern may leave a tip unseen (the coverage check speaks for that); a fit that
    overshoots the light does so at every tip."""
    if len(still) == 0:
        return math.inf
    gaps, _ = PointTree(still).query(outer_tips(fit))
    return float(np.median(gaps))


TIPS_LIT_WIDTHS = 0.5  # a right curve's tips lie within half a line width of the light's centre line
# a small loop is seen when its opening (width less one line width) is at least a line width wide
LOOP_SEEN_WIDTHS = 2.0
PROFILE_STEPS = 10  # fixed-b fits between the loops just closed and the fitted b
PROFILE_POINTS = 1500  # the profile is fitted on a seeded subsample of the trace


def tip_limited(fit: CurveFit, points: np.ndarray, weights: np.ndarray | None, times: np.ndarray | None,
                width: float) -> CurveFit | None:
    """A trochoid whose tips overshoot the light (:func:`tip_gap` over ``TIPS_LIT_WIDTHS`` line
    widths) while its small loops are not seen (:func:`loop_width` under ``LOOP_SEEN_WIDTHS`` line widths:
    the opening inside the loop is narrower than the line): the fit with b
    set by where the light ends, or None when this does not apply.

    The residual cannot fix b here: loops that grow into the thick spike of light pass ever
    closer to its edge, so it keeps falling as b grows. The tips can: the fit is repeated with b
    held at ``PROFILE_STEPS`` values from ``1/|k|`` (loops just closed) up to the fitted b
    (:func:`cusp_fit`), and each one's tip gap measured. Inside the light the gap stays at a
    floor (the spacing of the centre line); past the end of the light it grows in proportion to
    b. The b where the line through the overshooting fits meets the floor is where the tip
    reaches the end of the light; the result is the fit at that b. Times as in the fit (drift
    about their mean, which the result's centre refers to)."""
    p = fit.pattern
    if fit.k == -1 or not loop_width(fit.k, p.b, p.scale) < LOOP_SEEN_WIDTHS * width:
        return None
    pts = np.asarray(points, float)
    keep = np.random.default_rng(5).permutation(len(pts))[:PROFILE_POINTS]
    pts, wts = pts[keep], None if weights is None else np.asarray(weights, float)[keep]
    tms = None if times is None else np.asarray(times, float)[keep]
    tau = np.zeros(len(pts)) if tms is None else tms - tms.mean()
    z = pts[:, 0] + 1j * pts[:, 1]
    if tip_gap(fit, z - fit.drift * tau) <= TIPS_LIT_WIDTHS * width:
        return None
    bs = np.linspace(min(1.0 / abs(fit.k), p.b), p.b, PROFILE_STEPS)
    fits = [cusp_fit(fit, pts, wts, tms, b=b) for b in bs]
    gaps = np.array([tip_gap(f, z - f.drift * tau) for f in fits])
    b_end = _where_tips_leave_light(bs, gaps, TIPS_LIT_WIDTHS * width)
    if b_end is None:
        return None
    return cusp_fit(fits[int(np.argmin(np.abs(bs - b_end)))], pts, wts, tms, b=b_end)


def _where_tips_leave_light(bs: np.ndarray, gaps: np.ndarray, lit: float) -> float | None:
    """The b where the tip gap leaves its floor (the smallest gap): the straight line through the
    first two fits whose gap rose more than a quarter of ``lit`` above the floor meets the floor,
    kept between the last b still at the floor and the first b above it (the gap grows faster
    than linearly further out, so only the two fits nearest the kink set the line). With fewer
    than two such fits, the largest b at the floor. None when no fit keeps the tips within
    ``lit`` of the light."""
    if not (gaps <= lit).any():
        return None
    floor = float(gaps.min())
    rose = np.flatnonzero(gaps > floor + 0.25 * lit)  # bs ascending
    level = np.flatnonzero(gaps <= floor + 0.25 * lit)
    if len(rose) == 0:
        return float(bs[level[-1]])
    before = level[level < rose[0]]
    last_level = float(bs[before[-1]]) if len(before) else float(bs[0])
    if len(rose) < 2:
        return last_level
    (b1, b2), (g1, g2) = bs[rose[:2]], gaps[rose[:2]]
    slope = (g2 - g1) / (b2 - b1)
    if slope <= 0:
        return last_level
    return float(np.clip(b1 - (g1 - floor) / slope, last_level, b1))


def tips_in_light(cls: Classification, wander: Wander | None, points: np.ndarray, weights: np.ndarray | None,
                  times: np.ndarray | None, width: float) -> tuple[Classification, Wander | None]:
    """The classification (and the centre's wander, :mod:`labkit.vision.laser.wander`) with b set by
    where the light ends when :func:`tip_limited` applies, else both unchanged. The new fit's
    centre refers to the mean time of ``times``."""
    limited = tip_limited(cls.best, points, weights, times, width)
    if limited is None:
        return cls, wander
    t_ref = float(np.mean(times)) if times is not None else cls.t_ref
    if wander is not None:
        wander = replace(wander, fit=limited, t_ref=t_ref)
    return replace(cls, best=limited, t_ref=t_ref), wander
