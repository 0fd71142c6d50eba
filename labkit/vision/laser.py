"""Laser-trace analysis: frames -> accumulated trace -> pattern fit -> JSON-ready dict.

Per frame the only work is a running per-pixel maximum into the accumulator of the current time
chunk (about as cheap as decoding), so full analysis keeps pace with reading the video. Each
chunk's accumulation is then turned into trace points (:mod:`labkit.vision.trace`) stamped with
the chunk's mid time; the fit (:mod:`labkit.vision.fit`) carries a linear drift of the centre.
Tilt amplitudes: the reflected beam turns by twice the magnet's tilt, so a semi-axis ``r`` on a
screen at distance ``L`` is a tilt of ``atan(r / L) / 2`` (Sec. 5.2.3, Fig. 5.19/5.20).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import asdict, dataclass, replace

import cv2
import numpy as np

from labkit.vision.curves import a_for_k
from labkit.vision.exposure import check_exposure, grey_histogram
from labkit.vision.fit import MIN_POINTS, Classification, classify, pattern_kind
from labkit.vision.framepath import (
    AMPLE_LUMA_CNR,
    PROBE_FRAMES,
    FramePathChoice,
    luma_plane_cnr,
    measure_frame_path,
)
from labkit.vision.frames import FrameSource, open_frames
from labkit.vision.laser_checks import judged_width, laser_evidence, laser_verdict, no_pattern_verdict
from labkit.vision.loops_seen import tips_in_light
from labkit.vision.overlay import accumulated_trace
from labkit.vision.quality import rank
from labkit.vision.rescue import (
    one_chunk_start,
    pattern_moved_px,
    without_fixed_light,
    without_stray_light,
)
from labkit.vision.trace import TracePoints, trace_points
from labkit.vision.wander import Wander, follow_wander

FrameHook = Callable[[int, float, np.ndarray], None]
MAX_POINTS_PER_CHUNK = 4000
MIN_FRAMES_PER_CHUNK = 4
# a short clip is cut into at least this many chunks (when each keeps MIN_FRAMES_PER_CHUNK): a
# centre that wanders on a shaking tripod curves within a second, and 3 chunks of a 1.5 s clip
# put the middle chunk's mean centre 4 px from the centre at the middle of the recording (suite)
MIN_CHUNKS = 8


@dataclass
class LaserQuality:
    """Speed/accuracy settings: analyse every ``stride``-th frame, inside ``roi`` (x, y, w, h) or
    the whole frame (None), with or without sub-pixel refinement, accumulating ``chunk_s`` seconds
    of video per chunk (the time resolution of the centre's drift) but at most ``max_chunks``
    chunks (fewer chunks: faster; more: follows a fast drift better). ``luma``: None (auto)
    measures the trace's contrast-to-noise on the first frames in luma and in colour and uses the
    decoder's own luma plane (skips the colour conversion) only if luma keeps enough of it
    (:mod:`labkit.vision.framepath`); True forces luma where the codec has a luma plane; False
    forces the brightest colour channel of BGR frames. A live-stream hook always gets BGR."""

    stride: int = 1
    roi: tuple[int, int, int, int] | None = None
    subpixel: bool = True
    chunk_s: float = 0.5
    # long clips get longer chunks: trace extraction costs ~14 ms per 720p chunk. With the drift
    # fitted and the centre reported at the middle, 12 chunks follow a 7 px/s drift over 30 s to
    # 0.2 px; 16 cost 0.08 CPU-s more per clip for no measurable gain (docs/vision.md)
    max_chunks: int = 12
    luma: bool | None = None


@dataclass
class Chunk:
    image: np.ndarray
    offset: tuple[int, int]
    first: int
    last: int


def tilt_from_semi_axis(semi_axis_px: float, mm_per_px: float, screen_distance_mm: float) -> float:
    """Magnet tilt amplitude (rad) from a pattern semi-axis: the beam turns by twice the tilt."""
    return 0.5 * math.atan(semi_axis_px * mm_per_px / screen_distance_mm)


def _clip_roi(roi: tuple[int, int, int, int], size: tuple[int, int]) -> tuple[int, int, int, int]:
    x, y, w, h = (int(v) for v in roi)
    x0, y0 = max(0, x), max(0, y)
    x1, y1 = min(size[0], x + w), min(size[1], y + h)
    if x1 - x0 < 8 or y1 - y0 < 8:
        raise ValueError(f"region of interest {roi} lies outside the {size[0]}x{size[1]} frame")
    return x0, y0, x1 - x0, y1 - y0


def chunk_length(source: FrameSource, quality: LaserQuality) -> int:
    """Frames per chunk: ``chunk_s`` of video, shortened so that a short clip still has
    ``MIN_CHUNKS`` chunks to follow a wandering centre with (:mod:`labkit.vision.wander`); at
    least ``MIN_FRAMES_PER_CHUNK`` analysed frames, at most ``max_chunks`` chunks."""
    fps = source.fps or 30.0
    wanted = min(round(quality.chunk_s * fps), math.ceil(source.frame_count / MIN_CHUNKS))
    return max(MIN_FRAMES_PER_CHUNK * quality.stride, wanted,
               math.ceil(source.frame_count / max(1, quality.max_chunks)))


class FramePathProbe:
    """The ``choose_luma`` callback of automatic frame-path choice: keeps the measurement.
    :meth:`luma_is_ample` judges the first luma planes; only if it says no are the first
    frames decoded in colour as well and judged by the full rule (:meth:`__call__`)."""

    def __init__(self, roi: tuple[int, int, int, int] | None, frame_px: int) -> None:
        self.roi, self.frame_px = roi, frame_px
        self.choice: FramePathChoice | None = None

    def luma_is_ample(self, planes: list[np.ndarray]) -> bool:
        cnr = luma_plane_cnr(planes, self.roi, self.frame_px)
        if cnr < AMPLE_LUMA_CNR:
            return False
        self.choice = FramePathChoice(True, cnr, None)
        return True

    def __call__(self, frames: list[np.ndarray]) -> bool:
        self.choice = measure_frame_path(frames, self.roi, self.frame_px)
        return self.choice.luma


def accumulate(source: FrameSource, quality: LaserQuality, on_frame: FrameHook | None = None,
               on_chunk: Callable[[Chunk], None] | None = None, prefetch: int = 4,
               probe: FramePathProbe | None = None) -> list[Chunk]:
    """Running per-pixel maximum of the frames, one accumulator per ``quality.chunk_s`` of video
    (at least ``MIN_FRAMES_PER_CHUNK`` analysed frames, at most ``quality.max_chunks`` chunks).
    ``on_chunk`` gets each chunk as soon as it is complete; decoding runs ``prefetch`` frames
    ahead in a thread. With ``quality.luma`` None, ``probe`` (or a new :class:`FramePathProbe`)
    decides from the first frames whether the frames come as luma planes or in colour."""
    per_chunk = chunk_length(source, quality)
    fps = source.fps or 1.0
    roi = _clip_roi(quality.roi, source.size) if quality.roi is not None else None
    chunks: list[Chunk] = []
    luma = quality.luma is not False and on_frame is None
    auto = luma and quality.luma is None
    if auto and probe is None:
        probe = FramePathProbe(roi, max(source.size))
    for index, frame in source.frames(quality.stride, prefetch=prefetch, luma=luma,
                                      choose_luma=probe if auto else None, probe=PROBE_FRAMES):
        if on_frame is not None:
            on_frame(index, index / fps, frame)
        ci = index // per_chunk
        x, y, w, h = roi if roi is not None else (0, 0, *source.size)
        part = frame[y:y + h, x:x + w]
        new_chunk = not chunks or ci != chunks[-1].first // per_chunk
        if new_chunk:
            if chunks and on_chunk is not None:
                on_chunk(chunks[-1])
            chunks.append(Chunk(part.copy(), (x, y), index, index))
            continue
        c = chunks[-1]
        cv2.max(c.image, part, dst=c.image)
        c.last = index
    if chunks and on_chunk is not None:
        on_chunk(chunks[-1])
    return chunks


class TraceTracker:
    """Trace extraction chunk after chunk, looking only inside the box where the earlier chunks'
    traces were (the pattern drifts slowly) plus a margin of ``margin`` x the frame size. A trace
    that reaches the edge of that box, or has less than half the previous chunk's points, is
    extracted again from the whole chunk."""

    def __init__(self, frame_px: int, subpixel: bool, margin: float = 0.12) -> None:
        self.frame_px, self.subpixel = frame_px, subpixel
        self.pad = max(40, int(margin * frame_px))
        self.box: tuple[int, int, int, int] | None = None  # x0, y0, x1, y1 in frame px
        self.cropped = 0
        self.last_count = 0

    def extract(self, c: Chunk) -> TracePoints:
        tp = None
        if self.box is not None:
            ox, oy = c.offset
            h, w = c.image.shape[:2]
            x0, y0 = max(0, self.box[0] - ox), max(0, self.box[1] - oy)
            x1, y1 = min(w, self.box[2] - ox), min(h, self.box[3] - oy)
            if x1 - x0 > 16 and y1 - y0 > 16:
                tp = trace_points(c.image[y0:y1, x0:x1], (ox + x0, oy + y0), self.subpixel,
                                  frame_px=self.frame_px)
                inner = (ox + x0 + 3, oy + y0 + 3, ox + x1 - 4, oy + y1 - 4)
                edge = (x0 > 0, y0 > 0, x1 < w, y1 < h)
                if len(tp.points) < 0.5 * self.last_count or _touches(tp.points, inner, edge):
                    tp = None  # light may lie outside the box: look at the whole chunk
                else:
                    self.cropped += 1
        if tp is None:
            tp = trace_points(c.image, c.offset, self.subpixel, frame_px=self.frame_px)
        if len(tp.points):
            (px0, py0), (px1, py1) = tp.points.min(axis=0), tp.points.max(axis=0)
            box = (int(px0) - self.pad, int(py0) - self.pad, int(px1) + self.pad + 1, int(py1) + self.pad + 1)
            if self.box is not None:  # grow only: spots of one chunk may not span the whole pattern
                box = (min(box[0], self.box[0]), min(box[1], self.box[1]),
                       max(box[2], self.box[2]), max(box[3], self.box[3]))
            self.box = box
            self.last_count = len(tp.points)
        return tp


def _touches(points: np.ndarray, inner: tuple[float, float, float, float], edge: tuple[bool, ...]) -> bool:
    """Whether points reach a side of the box that is a crop (not the frame's own border)."""
    x, y = points[:, 0], points[:, 1]
    return bool((edge[0] and x.min() < inner[0]) or (edge[1] and y.min() < inner[1])
                or (edge[2] and x.max() > inner[2]) or (edge[3] and y.max() > inner[3]))


def _frame_path(chunks: list[Chunk], probe: FramePathProbe) -> dict:
    """``frame_path`` (what the last chunk was accumulated from) and the probe's CNRs (None when
    nothing was measured: forced path, photo, or a codec without a luma plane)."""
    path = "luma" if chunks[-1].image.ndim == 2 else "colour"
    if probe.choice is None:
        return {"frame_path": path, "cnr_luma": None, "cnr_colour": None}
    return {**probe.choice.to_quality(), "frame_path": path}


def _none(reason: str) -> dict:
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
    include the quality verdict (:mod:`labkit.vision.laser_checks`) when ``frame_size`` is given.
    With ``times``, the fitted centre drifts; it is reported at ``centre_time`` (s, e.g. the
    middle of the recording), or at the mean time of the points fitted.

    A result refined from ``prior`` (the first part's classification) that the checks do not
    call ``ok`` is done again from scratch, and the fresh result kept unless it ranks worse
    (:func:`labkit.vision.quality.rank`: a worse verdict, or the same with more checks not ``ok``):
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
    """The classification with the centre's wander followed (:mod:`labkit.vision.wander`), the
    wander, and the points with it taken out; unchanged (and the wander's offsets zero) when
    following it does not explain the trace clearly better (:attr:`Wander.needed`). A wander over
    half a line width (rms) blurs the accumulated trace enough to mislead the classification:
    the steadied points are then classified again and the wander followed anew."""
    width = judged_width(line_width_px)
    wander = follow_wander(cls, points, weights, times, width, band) if times is not None else None
    if wander is None:
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


def gather(chunks: list[Chunk], traces: list[TracePoints], fps: float):
    """Trace points of all chunks, stamped with their chunk's mid time: ``(points, weights,
    times, band, peak, noise)``; ``band`` is ``(pixels, weights, times)`` or None. Seeded
    subsampling keeps at most ``MAX_POINTS_PER_CHUNK`` centre-line points per chunk."""
    pts, wts, tms, bands = [], [], [], []
    peak = noise = 0.0
    rng = np.random.default_rng(0)
    for c, tp in zip(chunks, traces, strict=True):
        peak, noise = max(peak, tp.peak), max(noise, tp.noise)
        points, weights = tp.points, tp.weights
        if len(points) > MAX_POINTS_PER_CHUNK:
            keep = rng.choice(len(points), MAX_POINTS_PER_CHUNK, replace=False)
            points, weights = points[keep], weights[keep]
        t_mid = 0.5 * (c.first + c.last) / fps if fps else 0.0
        pts.append(points)
        wts.append(weights)
        tms.append(np.full(len(points), t_mid))
        if tp.band is not None and len(tp.band):
            keep = rng.choice(len(tp.band), min(len(tp.band), 2 * MAX_POINTS_PER_CHUNK), replace=False)
            bands.append((tp.band[keep], tp.band_weights[keep], np.full(len(keep), t_mid)))
    points = np.concatenate(pts) if pts else np.zeros((0, 2))
    band = tuple(np.concatenate(parts) for parts in zip(*bands, strict=True)) if bands else None
    return points, np.concatenate(wts), np.concatenate(tms), band, peak, noise


def line_width(traces: list[TracePoints]) -> float:
    """Median line width of the chunks' traces (NaN without any)."""
    widths = [t.line_width_px for t in traces if len(t.points)]
    return float(np.median(widths)) if widths else math.nan


def _second_readings(pattern: dict, diag: dict, points: np.ndarray, weights: np.ndarray, times: np.ndarray,
                     drift: bool, band: tuple | None, middle: float | None, width: float,
                     size: tuple[int, int]) -> tuple[dict, dict]:
    """The first fit is not ok: try the readings of :mod:`labkit.vision.rescue` in turn and keep
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
        *kept, share = moved
        fixed = pattern_dict(*kept, None, middle, width, size, (share, 0.0))
        if pattern_moved_px(fixed[1], kept[2]) > width and better(fixed):
            pattern, diag = fixed
            (points, weights, times, band), left_out, fixed_share = kept, (share, 0.0), share
    start = one_chunk_start(points, weights, times) if drift and diag["verdict"] != "ok" else None
    if start is not None:
        third = pattern_dict(points, weights, times, band, None, middle, width, size, left_out, start=start)
        if better(third):
            pattern, diag = third
    if fixed_share is not None:
        diag = {**diag, "light_fixed_in_frame": round(fixed_share, 4)}
    return pattern, diag


def _preliminary(chunks: list[Chunk], futures: list[Future], fps: float) -> Classification | None:
    """Classification of the first chunks (runs in the worker while later frames decode)."""
    points, weights, times, _, _, _ = gather(chunks, [f.result() for f in futures], fps)
    if len(points) < 10 * MIN_POINTS or not fps:
        return None
    return classify(points, weights, times)


def analyse_laser(path: str, screen_distance_mm: float | None = None, mm_per_px: float | None = None,
                  quality: LaserQuality | None = None, on_frame: FrameHook | None = None,
                  on_trace: Callable[[np.ndarray], None] | None = None,
                  on_progress: Callable[[int, int], None] | None = None) -> dict:
    """Analyse a laser-trace video or long-exposure photo; returns the ``labkit analyse laser`` JSON.

    ``on_frame(index, t_s, bgr)`` is called for every analysed frame (live streams hook in here;
    the frame buffer is reused, copy it to keep it). ``on_progress(frames_read, frame_count)``
    after each time chunk (``frame_count`` as the file says; 0 if unknown). ``on_trace(image)``
    gets the accumulated trace of the whole clip in a full frame (for :mod:`labkit.vision.overlay`).
    Raises :class:`VideoError` for unusable input; a usable file without a trace gives
    ``pattern.type == "none"`` with a reason.
    """
    quality = quality or LaserQuality()
    t_start = time.perf_counter()
    source = open_frames(path)
    fps = source.fps or 0.0
    per_chunk = chunk_length(source, quality)
    expected = math.ceil(source.frame_count / per_chunk) if source.frame_count > 0 else 0
    with ThreadPoolExecutor(max_workers=1) as pool:  # trace extraction overlaps decoding
        futures: dict[int, Future] = {}
        histograms: list[Future] = []
        tracker = TraceTracker(max(source.size), quality.subpixel)  # one worker: chunks in order
        done: list[Chunk] = []
        prior: dict[str, Future] = {}

        def extract(c: Chunk) -> None:
            futures[id(c)] = pool.submit(tracker.extract, c)
            histograms.append(pool.submit(grey_histogram, c.image))
            done.append(c)
            if on_progress is not None:
                on_progress(c.last + 1, max(source.frame_count, 0))
            if expected >= 4 and len(done) == expected // 2:
                # classify the first half while the second half decodes; the end only refines
                prior["fit"] = pool.submit(_preliminary, list(done), [futures[id(d)] for d in done], fps)

        probe = FramePathProbe(_clip_roi(quality.roi, source.size) if quality.roi is not None else None,
                               max(source.size))
        chunks = accumulate(source, quality, on_frame, on_chunk=extract, probe=probe)
        t_frames = time.perf_counter()
        check_exposure(sum(h.result() for h in histograms), source.path, source.levels)
        traces = [futures[id(c)].result() for c in chunks]
        preliminary = prior["fit"].result() if "fit" in prior else None
    points, weights, times, band, peak, noise = gather(chunks, traces, fps)
    if on_trace is not None:
        on_trace(accumulated_trace(chunks, source.size))
    qual = {"frames_analysed": len(range(0, source.frames_read, quality.stride)),
            "stride": quality.stride, "roi": list(chunks[-1].offset) + list(chunks[-1].image.shape[1::-1]),
            "subpixel": quality.subpixel, "chunks": len(chunks), "trace_points": int(len(points)),
            "peak_level": peak, "noise_level": noise, "truncated": source.truncated,
            "chunks_searched_near_previous_trace": tracker.cropped,
            **_frame_path(chunks, probe)}
    if len(points) < MIN_POINTS:
        reason = ("no light above the background noise" if len(points) == 0
                  else f"only {len(points)} trace pixels found")
        pattern, tilt = _none(reason), None
        qual = {**no_pattern_verdict(reason), **qual}
    else:
        drift = len(chunks) > 1 and fps
        if band is not None and not drift:
            band = (band[0], band[1], None)
        middle = (source.frames_read - 1) / (2 * fps) if fps else None
        width = line_width(traces)
        pattern, diag = pattern_dict(points, weights, times if drift else None, band, preliminary, middle,
                                     width, tuple(source.size))
        if diag["verdict"] != "ok":
            pattern, diag = _second_readings(pattern, diag, points, weights, times, bool(drift), band,
                                             middle, width, tuple(source.size))
        qual = {**{k: diag[k] for k in ("verdict", "reasons", "checks")}, **qual, **diag}
        tilt = None
        if screen_distance_mm and mm_per_px:
            major, minor = pattern["semi_axes_px"]
            tilt = {"major": tilt_from_semi_axis(major, mm_per_px, screen_distance_mm),
                    "minor": tilt_from_semi_axis(minor, mm_per_px, screen_distance_mm)}
    qual["settings"] = asdict(quality)
    qual["elapsed_s"] = time.perf_counter() - t_start
    qual["fit_s"] = time.perf_counter() - t_frames  # work left after the last frame: mostly the fit
    return {"source": source.path, "frames": source.frames_read, "fps": fps, "size": list(source.size),
            "pattern": pattern, "tilt_rad": tilt, "quality": qual}
