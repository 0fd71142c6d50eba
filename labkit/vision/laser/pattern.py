"""The fit side of the laser analysis (:mod:`labkit.vision.laser.analyse`): the gathered trace
points -> classification (:mod:`labkit.vision.laser.pattern_fit`), the centre's wander
(:mod:`labkit.vision.laser.wander`), the checks and verdict (:mod:`labkit.vision.laser.checks`) and
second readings (:mod:`labkit.vision.laser.second_reading`) -> the JSON
``pattern`` object and its diagnostics.

Kept apart from the frame side so that ``labkit analyse laser`` starts decoding before these
modules load: :func:`labkit.vision.laser.analyse.analyse_laser` imports this module in its worker thread
while the first frames decode (docs/explanation/vision-throughput.md, *The whole command*). Tilt amplitudes
and the trochoid parameters follow Sec. 5.2.3 and Eq. 6.38 (see :mod:`labkit.vision.shared.curves`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from labkit.vision.laser.checks import judged_width, laser_evidence, laser_verdict, no_pattern_verdict
from labkit.vision.laser.gather import GatheredTrace
from labkit.vision.laser.loops_seen import tips_in_light
from labkit.vision.laser.pattern_fit import MIN_POINTS, Classification, classify, pattern_kind
from labkit.vision.laser.second_reading import (
    one_chunk_start,
    pattern_moved_px,
    without_fixed_light,
    without_stray_light,
)
from labkit.vision.laser.wander import Wander, follow_wander
from labkit.vision.shared.curves import a_for_k
from labkit.vision.shared.verdict import rank


def read_pattern(points: np.ndarray, weights: np.ndarray, times: np.ndarray, drift: bool, band: tuple | None,
                 prior: Classification | None, middle: float | None, width: float,
                 size: tuple[int, int]) -> tuple[dict, dict]:
    """The ``pattern`` object and the diagnostics with the verdict of a trace of at least
    ``MIN_POINTS`` points (:func:`pattern_dict`, with the centre drifting when ``drift``), and
    when that is not ``ok`` the best of the second readings."""
    pattern, diag = pattern_dict(points, weights, times if drift else None, band, prior, middle, width, size)
    if diag["verdict"] != "ok":
        pattern, diag = _second_readings(pattern, diag, points, weights, times, drift, band, middle, width,
                                         size)
    return pattern, diag


def unreadable(points: np.ndarray) -> tuple[dict, dict] | None:
    """The ``pattern`` object and verdict of a trace with fewer than ``MIN_POINTS`` points (None
    for a trace that can be read)."""
    if len(points) >= MIN_POINTS:
        return None
    reason = ("no light above the background noise" if len(points) == 0
              else f"only {len(points)} trace pixels found")
    return no_pattern(reason), no_pattern_verdict(reason)


def no_pattern(reason: str) -> dict:
    """The ``pattern`` object of a clip without a usable trace, with the reason."""
    return {"type": "none", "reason": reason, "center_px": None, "semi_axes_px": None,
            "rotation_deg": None, "ellipticity": None, "loops": None, "symmetry": None, "trochoid": None,
            "rms_residual_px": None}


def symmetry_of(kind: str, k: int) -> int | None:
    """n-fold rotational symmetry of a pattern: round(1/|a|) = |k - 1| of Eq. 6.38 (a trochoid
    with ``loops`` n: n - 1 for an epitrochoid, n for a hypotrochoid), 2 for an ellipse, None for
    a circle (every rotation maps it onto itself)."""
    if kind == "circle":
        return None
    return round(1.0 / abs(a_for_k(k)))


def pattern_dict(points: np.ndarray, weights: np.ndarray, times: np.ndarray | None,
                 band: tuple | None = None, prior: Classification | None = None,
                 centre_time: float | None = None, line_width_px: float = math.nan,
                 frame_size: tuple[int, int] | None = None, left_out: tuple[float, float] = (0.0, 0.0),
                 start: Classification | None = None) -> tuple[dict, dict]:
    """Classify and fit a trace; returns the JSON ``pattern`` object and fit diagnostics, which
    include the quality verdict (:mod:`labkit.vision.laser.checks`) when ``frame_size`` is given.
    With ``times``, the fitted centre drifts; it is reported at ``centre_time`` (s, e.g. the
    middle of the recording), or at the mean time of the points fitted.

    A result refined from ``prior`` (the first part's classification) that the checks do not
    call ``ok`` is done again from scratch, and the fresh result kept unless it ranks worse
    (:func:`labkit.vision.shared.verdict.rank`: a worse verdict, or the same with more checks not ``ok``):
    the first part may have shown too little of the pattern."""
    args = (centre_time, line_width_px, frame_size, left_out)
    pattern, diag = _pattern_dict(points, weights, times, band, prior, *args, start)
    if prior is not None and diag.get("verdict", "ok") != "ok":
        fresh = _pattern_dict(points, weights, times, band, None, *args, None)
        if rank(fresh[1]) <= rank(diag):
            return fresh
    return pattern, diag


def _pattern_dict(points: np.ndarray, weights: np.ndarray, times: np.ndarray | None, band: tuple | None,
                  prior: Classification | None, centre_time: float | None, line_width_px: float,
                  frame_size: tuple[int, int] | None, left_out: tuple[float, float],
                  start: Classification | None) -> tuple[dict, dict]:
    cls = start if start is not None else classify(points, weights, times, band=band, prior=prior)
    cls, wander, points = _steadied(cls, points, weights, times, band, line_width_px)
    before = cls.best
    cls, wander = tips_in_light(cls, wander, points, weights, times, judged_width(line_width_px))
    best, ell = cls.best, cls.ellipse.pattern
    centre = best.c
    if times is not None and centre_time is not None:
        centre = wander.centre_at(centre_time) if wander else centre + best.drift * (centre_time - cls.t_ref)
    major, minor = ell.semi_axes
    kind = pattern_kind(cls.best)
    p = best.pattern
    trochoid = None
    if p.kind in ("epitrochoid", "hypotrochoid"):
        # extent of a trochoid: |z - c| runs between scale (1 - b) and scale (1 + b)
        axes, ellipticity = [p.scale * (1 + p.b), p.scale * abs(1 - p.b)], None
        rotation = math.degrees(p.rotation_rad)
        trochoid = {"a": a_for_k(best.k), "b": p.b, "scale_px": p.scale, "rotation_deg": rotation}
        loops = p.loops
    else:
        axes, ellipticity = [major, minor], (1 - minor / major if major > 0 else 0.0)
        rotation, loops = math.degrees(ell.rotation_rad), 1
    pattern = {"type": kind, "center_px": [float(centre.real), float(centre.imag)], "semi_axes_px": axes,
               "rotation_deg": rotation, "ellipticity": ellipticity,
               "loops": loops, "symmetry": symmetry_of(kind, best.k), "trochoid": trochoid,
               "rms_residual_px": best.rms_residual}
    residuals = {k: (v if math.isfinite(v) else None) for k, v in cls.residuals.items()}
    coverage = {k: (v if math.isfinite(v) else None) for k, v in cls.coverage.items()}
    diag = {"drift_px_s": [float(best.drift.real), float(best.drift.imag)],
            "wander_px": None if wander is None else {"rms": round(wander.rms_px, 3), "chunk_offsets": [
                [round(float(o.real), 3), round(float(o.imag), 3)] for o in wander.offsets]},
            "candidate_residuals_px": residuals, "candidate_coverage_px": coverage,
            "b_from_tips": None if best is before else {"fitted_b": before.pattern.b, "b": best.pattern.b}}
    if frame_size is not None:
        evidence = {**laser_evidence(cls, points, times, line_width_px, frame_size, wander),
                    "light_left_out": round(left_out[0], 4), "left_out_rival": round(left_out[1], 4)}
        diag = {**laser_verdict(evidence, frame_size), **diag}
    return pattern, diag


def _steadied(cls: Classification, points: np.ndarray, weights: np.ndarray, times: np.ndarray | None,
              band: tuple | None, line_width_px: float) -> tuple[Classification, Wander | None, np.ndarray]:
    """The classification with the centre's wander followed (:mod:`labkit.vision.laser.wander`), the
    wander, and the points with it taken out; unchanged (and the wander's offsets zero) when
    following it does not explain the trace clearly better (:attr:`Wander.needed`). A wander over
    half a line width (rms) blurs the accumulated trace enough to mislead the classification:
    the steadied points are then classified again and the wander followed anew."""
    width = judged_width(line_width_px)
    wander = follow_wander(cls, points, weights, times, width, band) if times is not None else None
    if wander is None or times is None:   # a wander is followed only with the points' times
        return cls, None, points
    if wander.rms_px > 0.5 * width:
        again = classify(wander.moved(points, times), weights, times)
        followed = follow_wander(again, points, weights, times, width, band)
        if followed is not None and followed.needed:
            wander, cls = followed, again
    if not wander.needed:
        straight = replace(wander, offsets=np.zeros_like(wander.offsets), fit=cls.best, t_ref=cls.t_ref)
        return cls, straight, points
    chosen = wander.fit
    ellipse = chosen if chosen.k == -1 else replace(cls.ellipse, c=cls.ellipse.c + cls.ellipse.drift
                                                     * (wander.t_ref - cls.t_ref))
    return replace(cls, best=chosen, ellipse=ellipse, t_ref=wander.t_ref), wander, wander.moved(points, times)


def _second_readings(pattern: dict, diag: dict, points: np.ndarray, weights: np.ndarray, times: np.ndarray,
                     drift: bool, band: tuple | None, middle: float | None, width: float,
                     size: tuple[int, int]) -> tuple[dict, dict]:
    """The first fit is not ok: try the readings of :mod:`labkit.vision.laser.second_reading` in turn and keep
    whichever gives the best verdict, on the same verdict the one with fewer reasons (the first
    fit on a full tie)."""
    def better(candidate: tuple[dict, dict]) -> bool:  # on the same verdict: fewer reasons to doubt
        return rank(candidate[1]) < rank(diag)

    everything = (points, weights, times, band)
    *parts, left_out = without_stray_light(points, weights, times, band, width)
    # the pattern is most of the light, or what was left out is many small things (a timestamp's
    # characters); otherwise this may be a fragment of it
    if left_out[0] > 0 and (left_out[0] < 0.5 or left_out[1] < 0.5):
        points, weights, times, band = parts
        second = pattern_dict(points, weights, times if drift else None, band, None, middle, width, size,
                              left_out)
        if better(second):
            pattern, diag = second
    else:
        left_out = (0.0, 0.0)
    fixed_share = None
    moved = without_fixed_light(*everything, width) if drift and diag["verdict"] != "ok" else None
    if moved is not None:  # light fixed in the frame, if the pattern moved, is not on the screen
        kept_points, kept_weights, kept_times, kept_band, share = moved
        fixed = pattern_dict(kept_points, kept_weights, kept_times, kept_band, None, middle, width, size,
                             (share, 0.0))
        if pattern_moved_px(fixed[1], kept_times) > width and better(fixed):
            pattern, diag = fixed
            points, weights, times, band = kept_points, kept_weights, kept_times, kept_band
            left_out, fixed_share = (share, 0.0), share
    start = one_chunk_start(points, weights, times) if drift and diag["verdict"] != "ok" else None
    if start is not None:
        third = pattern_dict(points, weights, times, band, None, middle, width, size, left_out, start=start)
        if better(third):
            pattern, diag = third
    if fixed_share is not None:
        diag = {**diag, "light_fixed_in_frame": round(fixed_share, 4)}
    return pattern, diag


def preliminary(gathered: GatheredTrace, chunks: int, fps: float) -> Classification | None:
    """Classification of the first ``chunks`` chunks (runs in the worker while later frames
    decode, after those chunks' traces were gathered)."""
    points, weights, times, _, _, _ = gathered.result(chunks)
    if len(points) < 10 * MIN_POINTS or not fps:
        return None
    return classify(points, weights, times)
