"""Evidence about a laser-pattern fit, and the quality verdict it supports (docs/reference/vision-verdicts.md,
"Quality verdict"). Every measure is one a reviewer would read off an overlay of the fitted
curve on the trace, expressed in units that do not depend on the footage: the trace's own line
width, fractions of the curve and of the light, the frame's size.

* residual: rms distance of the trace's centre line from the curve, in line widths. A right
  curve runs inside the light (well under half a line width); a wrong one leaves it.
* curve covered: the share of the curve's length that has light within a line width. A curve
  with loops the trace does not have (more loops, a 3x scale) runs through dark screen; a short
  clip of short arcs leaves part of the pattern unseen, and the fit extrapolates there (a
  symmetric copy of the unseen part does not stand in for it: an arc and its copy on the other
  side are what pin down the centre and the size).
* light explained: the share of trace points within 1.5 line widths of the curve (a stray
  reflection or a second pattern is light the curve does not explain; the centre line of a right
  fit stays within half a width, its spurs where lines cross within about one).
* extent: how far the light reaches from the centre (99.5th percentile, on points within three
  line widths of the curve) against how far the curve reaches. The centre line runs to the tips
  of the light, so a right curve matches it within a line width (spurs of a saturated halo at
  slow tips reach about that far, as for light explained); tips that overshoot or fall short of
  the light by more than 1.5 widths are extrapolated (thick hypotrochoid tips, loops the light
  fills).
* size: the curve against the frame (a semi-axis larger than the frame is not a pattern).
* tips lit: how far the fitted curve's outer tips lie from the nearest light, in line widths
  (:func:`labkit.vision.laser.loops_seen.tip_gap`). A right curve's tips lie on the centre line of the
  light (within half a line width, as the residual); a fit whose small loops grew larger than the
  light shows, as on a thick line whose loops are filled in (the opening inside a loop,
  :func:`labkit.vision.laser.loops_seen.loop_width` less a line width, narrower than the line),
  reaches past the end of the light while its residual still looks good: its outer extent and
  b are extrapolated. (Such a fit is first corrected, :func:`labkit.vision.laser.loops_seen.tip_limited`.)
* conditioning: a trochoid's second term (``b`` x scale) against the line width; under one line
  width the small loops are not formed and ``loops``, ``a`` and ``b`` are not determined.
* light left out: light set apart as lying away from the pattern (:mod:`labkit.vision.laser.stray_light`:
  a burnt-in timestamp, a stray reflection). Small, compact or far light is clearly not the
  pattern, however many points it has (a timestamp is dense text); when its largest part is at
  least half the pattern's size (points x extent), which light is the pattern is a guess.
* runner-up: how close the best different pattern came, on the score that ranks trochoids
  (:func:`labkit.vision.laser.pattern_fit.two_way_rms`).
* steadiness: how far each time chunk's trace sits from the fitted curve as a whole (a wandering
  or shaking centre the centre model does not follow): the result is then an average.
* straight drift: a pattern that moved more than a line width over the clip, in a clip where too
  few time chunks show enough of the pattern to follow the centre chunk by chunk
  (:mod:`labkit.vision.laser.wander`): its centre and size rest on the assumption of a straight drift.
"""

from __future__ import annotations

import math

import numpy as np

from labkit.vision.laser.loops_seen import LOOP_SEEN_WIDTHS, TIPS_LIT_WIDTHS, loop_width, tip_gap
from labkit.vision.laser.nearest import PointTree
from labkit.vision.laser.pattern_fit import Classification, CurveFit, coverage_rms, two_way_rms
from labkit.vision.laser.wander import Wander, chunk_offsets, dense_curve
from labkit.vision.shared.verdict import Finding, Verdict, graded

MIN_LINE_WIDTH_PX = 2.0  # a trace is never judged against less than this (sub-pixel lines)
# a different pattern whose score is within this factor of the chosen one's is a real alternative
RUNNER_UP_FACTOR = 1.25
MAX_EVIDENCE_POINTS = 4000
LIGHT_NEAR_WIDTHS = 1.5  # trace points within this many line widths of the curve are explained
EXTENT_NEAR_WIDTHS = 3.0  # the light's reach is measured on points this close to the curve


def judged_width(line_width_px: float) -> float:
    """The line width a trace is judged against: the measured one, at least ``MIN_LINE_WIDTH_PX``."""
    return max(MIN_LINE_WIDTH_PX, float(line_width_px) if math.isfinite(line_width_px) else 0.0)


def _name(fit: CurveFit) -> str:
    p = fit.pattern
    return "ellipse" if fit.k == -1 else f"{p.kind}-{p.loops}"


def _steadiness_px(fit: CurveFit, still: np.ndarray, times: np.ndarray | None, width: float) -> float:
    """Rms of the chunks' offsets from the fitted curve (see :mod:`labkit.vision.laser.wander`) that the
    fit's centre model left: 0 for a photo or fewer than 3 chunks."""
    if times is None:
        return 0.0
    mid_times, chunk = np.unique(times, return_inverse=True)
    if len(mid_times) < 3:
        return 0.0
    offsets = chunk_offsets(fit, still, chunk, len(mid_times), width)
    offsets = offsets[np.isfinite(offsets)]
    if len(offsets) < 3:
        return 0.0
    return float(np.sqrt(np.mean(np.abs(offsets - offsets.mean()) ** 2)))


def laser_evidence(cls: Classification, points: np.ndarray, times: np.ndarray | None,
                   line_width_px: float, frame_size: tuple[int, int], wander: Wander | None = None) -> dict:
    """The measures of the module docstring for the chosen fit ``cls.best`` (JSON-ready);
    ``wander``: the centre's wander as followed (:func:`labkit.vision.laser.wander.follow_wander`)."""
    best = cls.best
    keep = np.random.default_rng(3).permutation(len(points))[:MAX_EVIDENCE_POINTS]
    pts = np.asarray(points, float)[keep]
    tms = None if times is None else np.asarray(times, float)[keep]
    tau = np.zeros(len(pts)) if tms is None else tms - cls.t_ref
    still = pts[:, 0] + 1j * pts[:, 1] - best.drift * tau
    width = judged_width(line_width_px)
    curve, share = dense_curve(best)
    light_to_curve, _ = PointTree(curve).query(still)
    curve_to_light, _ = PointTree(still).query(curve)
    radius = np.abs(curve - best.c)
    near = light_to_curve <= EXTENT_NEAR_WIDTHS * width
    reach = np.abs(still[near] - best.c)
    light_reach = float(np.percentile(reach, 99.5)) if len(reach) else float(radius.max())
    w, h = frame_size
    outside = max(0.0, float(-curve.real.min()), float(curve.real.max() - (w - 1)),
                  float(-curve.imag.min()), float(curve.imag.max() - (h - 1)))
    steadiness = _steadiness_px(best, still, tms, width)
    runner = _runner_up(cls, width, pts, tau)
    return {
        "line_width_px": round(width, 3),
        "residual_line_widths": round(best.rms_residual / width, 4),
        "curve_covered": round(float(np.sum(share[curve_to_light <= width])), 4),
        "light_explained": round(float(np.mean(light_to_curve <= LIGHT_NEAR_WIDTHS * width)), 4),
        "largest_radius_px": round(float(radius.max()), 2),
        "extent_mismatch_line_widths": round((light_reach - float(radius.max())) / width, 3),
        "curve_outside_frame_px": round(outside, 2),
        "second_term_line_widths": None if best.k == -1 else round(abs(best.b) / width, 3),
        "tip_gap_line_widths": round(tip_gap(best, still) / width, 3),
        "loop_width_line_widths": None if best.k == -1 else round(
            loop_width(best.k, best.pattern.b, best.pattern.scale) / width, 3),
        "runner_up": runner,
        "chunk_wander_px": round(steadiness, 3),
        "centre_travel_px": round(_travel_px(best, times), 3),
        "chunks_checked": None if wander is None else wander.chunks_checked,
    }


def _travel_px(fit: CurveFit, times: np.ndarray | None) -> float:
    """How far the fitted drift moves the centre over the clip (first to last chunk)."""
    if times is None or not len(times):
        return 0.0
    return float(abs(fit.drift) * (np.max(times) - np.min(times)))


def _runner_up(cls: Classification, width: float, pts: np.ndarray, tau: np.ndarray) -> dict | None:
    """The best different pattern and its score against the chosen one's (both on the same
    points). A candidate whose curve stays within a line width of the chosen one (a trochoid
    with loops too small to see, against an ellipse) is the same answer and does not count; a
    'ratio' under 1 means a different pattern scored better but lost to the rule that prefers
    the simpler pattern."""
    best = cls.best
    z = pts[:, 0] + 1j * pts[:, 1]
    candidates = [cls.ellipse] + list(cls.fits.values())
    own_curve, _ = dense_curve(best, 1.0)
    own_tree = PointTree(own_curve)
    alternatives = []
    for f in candidates:
        if _name(f) == _name(best) or not math.isfinite(f.rms_residual):
            continue
        if _departure(f, own_curve, own_tree) <= width:
            continue  # the same curve within a line width (a trochoid with invisible loops)
        alternatives.append(f)
    if not alternatives:
        return None

    def scores(f: CurveFit) -> tuple[float, float]:
        residual = _residual(f, z, tau)
        return two_way_rms(residual, coverage_rms(f, z, tau)), residual

    own, own_residual = scores(best)
    ranked = sorted(alternatives, key=lambda f: two_way_rms(f.rms_residual, cls.coverage.get(_name(f), 0.0)))
    scored = [(scores(f), f) for f in ranked[:3]]
    (other_score, other_residual), other = min(scored, key=lambda item: item[0][0])
    return {"pattern": _name(other), "score_px": round(other_score, 3), "chosen_score_px": round(own, 3),
            "ratio": round(other_score / max(own, 1e-9), 3), "residual_px": round(other_residual, 3),
            "chosen_residual_px": round(own_residual, 3)}


def _departure(fit: CurveFit, other: np.ndarray, other_tree: PointTree) -> float:
    """How far two curves visibly differ: the larger of the 90th percentiles of the distances
    from each to the other (px)."""
    mine, _ = dense_curve(fit, 1.0)
    there, _ = other_tree.query(mine)
    back, _ = PointTree(mine).query(other)
    return float(max(np.percentile(there, 90), np.percentile(back, 90)))


def _residual(fit: CurveFit, z: np.ndarray, tau: np.ndarray) -> float:
    curve, _ = dense_curve(fit, 0.5)
    d, _ = PointTree(curve).query(z - fit.drift * tau)
    return float(np.sqrt(np.mean(d * d)))


def laser_findings(evidence: dict, frame_size: tuple[int, int]) -> list[Finding]:
    """The checks of the module docstring as :class:`Finding` objects."""
    w, h = frame_size
    width = evidence["line_width_px"]
    mismatch = evidence["extent_mismatch_line_widths"]
    out = [
        graded("residual", evidence["residual_line_widths"], 0.5, 2.0,
               "the trace lies {value:.1f} line widths (rms) from the fitted curve"),
        graded("curve covered", 1.0 - evidence["curve_covered"], 1 / 3, 2 / 3,
               f"only {100 * evidence['curve_covered']:.0f} % of the fitted curve has light on it "
               "(the rest is extrapolated)"),
        graded("light explained", 1.0 - evidence["light_explained"], 0.05, 0.5,
               f"{100 * (1 - evidence['light_explained']):.0f} % of the light lies off the fitted curve "
               "(a stray reflection, a second pattern, or the wrong pattern)"),
        graded("extent", abs(mismatch), LIGHT_NEAR_WIDTHS, math.inf,
               f"the fitted curve reaches {abs(mismatch):.1f} line widths "
               f"{'short of' if mismatch > 0 else 'beyond'} the farthest light from the centre: "
               "the extent (semi-axes, tips) is extrapolated, not measured"),
        graded("size", evidence["largest_radius_px"] / math.hypot(w, h), 0.5, 1.0,
               f"the fitted curve reaches {evidence['largest_radius_px']:.0f} px from its centre "
               f"on a {w}x{h} frame"),
        graded("inside frame", evidence["curve_outside_frame_px"] / min(w, h), 0.02, 0.25,
               f"the fitted curve runs {evidence['curve_outside_frame_px']:.0f} px outside the frame"),
        graded("steadiness", evidence["chunk_wander_px"] / width, 0.5, math.inf,
               f"the trace moves {evidence['chunk_wander_px']:.1f} px (rms) between parts of the clip "
               "beyond a steady drift (shaking camera or wandering centre): centre and size are averages"),
    ]
    left_out, rival = evidence.get("light_left_out", 0.0), evidence.get("left_out_rival", 0.0)
    out.append(graded("light left out", rival, 0.5, math.inf,
                      f"{100 * left_out:.0f} % of the light lies away from the pattern and was left out, "
                      f"and its largest part is {rival:.1f}x the pattern's size (points x extent): which "
                      "light is the pattern is a guess"))
    if evidence["chunks_checked"] is not None and evidence["chunks_checked"] < 3:
        out.append(graded("straight drift", evidence["centre_travel_px"] / width, 1.0, math.inf,
                          f"the pattern moved {evidence['centre_travel_px']:.0f} px over the clip, and too "
                          "few parts of the clip show enough of the pattern to check that it moved in a "
                          "straight line (short arcs per frame): centre and size assume it did"))
    out.append(_tips_lit(evidence))
    if evidence["second_term_line_widths"] is not None:
        second = evidence["second_term_line_widths"]
        out.append(graded("conditioning", 1.0 / max(second, 1e-9), 1.0, math.inf,
                          f"the small loops are barely formed (second term {second:.2f} line widths of "
                          f"{width:.1f} px): loop count, a and b are poorly determined"))
    runner = evidence["runner_up"]
    if runner is not None and runner_up_is_close(runner, width):
        out.append(Finding("runner-up", "doubtful",
                           f"{runner['pattern']} explains the trace nearly as well "
                           f"(score {runner['score_px']:.2f} px against {runner['chosen_score_px']:.2f} px)"))
    return out


def _tips_lit(evidence: dict) -> Finding:
    """The *tips lit* check: the curve's outer tips must lie on the light."""
    gap, loop = evidence["tip_gap_line_widths"], evidence["loop_width_line_widths"]
    unseen = loop is not None and 0 < loop < LOOP_SEEN_WIDTHS
    filled = ("; the opening of its small loops is narrower than the line (filled in, not seen), so the "
              "light does not show how large they are" if unseen else "")
    return graded("tips lit", gap, TIPS_LIT_WIDTHS, math.inf,
                  "the fitted curve's outer tips lie {value:.1f} line widths beyond the nearest light: "
                  "the outer extent (semi-axes) and b are extrapolated, not measured" + filled)


def runner_up_is_close(runner: dict, width: float) -> bool:
    """Whether the trace fails to tell the runner-up from the chosen pattern: its two-way score is
    within ``RUNNER_UP_FACTOR`` of the chosen one's, and its residual is not clearly larger (at
    most twice the chosen one's, or a quarter line width more). Scores share the part of a curve
    that no light covers; residuals do not, and on a clean trace they separate patterns whose
    scores an unseen stretch of the curve makes look alike."""
    own = runner["chosen_residual_px"]
    near = runner["residual_px"] <= max(2 * own, own + 0.25 * width)
    return bool(runner["ratio"] < RUNNER_UP_FACTOR and near)


def laser_verdict(evidence: dict, frame_size: tuple[int, int]) -> dict:
    """``{"verdict", "reasons", "checks", ...evidence}`` for a fitted pattern."""
    return {**Verdict.of(laser_findings(evidence, frame_size)).as_json(), **evidence}


def no_pattern_verdict(reason: str) -> dict:
    """The verdict of a usable file without a trace."""
    return Verdict.of([Finding("trace", "failed", reason)]).as_json()

