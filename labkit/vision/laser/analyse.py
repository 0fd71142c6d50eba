"""Laser-trace analysis: frames -> accumulated trace -> pattern fit -> JSON-ready dict.

Per frame the only work is a running per-pixel maximum into the accumulator of the current time
chunk (about as cheap as decoding), so full analysis keeps pace with reading the video. Each
chunk's accumulation is then turned into trace points (:mod:`labkit.vision.laser.trace`) stamped with
the chunk's mid time; the fit (:mod:`labkit.vision.laser.pattern_fit`) carries a linear drift of the centre.
Tilt amplitudes: the reflected beam turns by twice the magnet's tilt, so a semi-axis ``r`` on a
screen at distance ``L`` is a tilt of ``atan(r / L) / 2`` (Sec. 5.2.3, Fig. 5.19/5.20).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

from labkit.vision.laser.frame_path import (
    AMPLE_LUMA_CNR,
    PROBE_FRAMES,
    FramePathChoice,
    luma_plane_cnr,
    measure_frame_path,
)
from labkit.vision.laser.gather import MAX_POINTS_PER_CHUNK, GatheredTrace, gather  # noqa: F401 (API)
from labkit.vision.laser.result import LaserPattern, LaserResult, TiltAngles
from labkit.vision.laser.scene_kind import scene_measures, strobe_scene_verdict
from labkit.vision.laser.trace import TracePoints, trace_points
from labkit.vision.shared.exposure import check_exposure, grey_histogram
from labkit.vision.shared.frames import FrameSource, open_frames
from labkit.vision.shared.verdict import QualityReport, Verdict

if TYPE_CHECKING:
    from concurrent.futures import Future, ThreadPoolExecutor

    from labkit.vision.laser.pattern_fit import Classification

# The fit side (labkit.vision.laser.pattern: the fit, wander, checks, second readings) loads in
# the worker thread while the first frames decode, not before the first frame; its public
# functions stay importable from here.
_FIT_SIDE = ("pattern_dict", "symmetry_of", "read_pattern")


def __getattr__(name: str):
    if name in _FIT_SIDE:
        from labkit.vision.laser import pattern as laser_pattern

        return getattr(laser_pattern, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


FrameHook = Callable[[int, float, np.ndarray], None]
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
    (:mod:`labkit.vision.laser.frame_path`); True forces luma where the codec has a luma plane; False
    forces the brightest colour channel of BGR frames. A live-stream hook always gets BGR."""

    stride: int = 1
    roi: tuple[int, int, int, int] | None = None
    subpixel: bool = True
    chunk_s: float = 0.5
    # long clips get longer chunks: trace extraction costs ~14 ms per 720p chunk. With the drift
    # fitted and the centre reported at the middle, 12 chunks follow a 7 px/s drift over 30 s to
    # 0.2 px; 16 cost 0.08 CPU-s more per clip for no measurable gain (docs/explanation/laser-analysis.md)
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


def tilt_geometry_doubt(semi_axis_px: float, mm_per_px: float, screen_distance_mm: float) -> str | None:
    """Why a tilt from these numbers is doubtful, or None. A semi-axis on the screen longer than
    the screen distance is a beam turned by more than 45 deg (a tilt above 22.5 deg, beyond the
    paper's cones); it is what a distance typed in metres gives (``--screen-distance-mm 0.5``)."""
    semi_axis_mm = semi_axis_px * mm_per_px
    if semi_axis_mm <= screen_distance_mm:
        return None
    hint = (f"; a distance typed in metres? ({screen_distance_mm:g} m = {screen_distance_mm * 1e3:g} mm)"
            if screen_distance_mm < 10 <= screen_distance_mm * 1e3 else "")
    return (f"the trace's semi-axis on the screen ({semi_axis_mm:.3g} mm) is longer than the screen "
            f"distance ({screen_distance_mm:g} mm): the tilt "
            f"{math.degrees(tilt_from_semi_axis(semi_axis_px, mm_per_px, screen_distance_mm)):.1f} deg "
            f"is above 22.5 deg; check --screen-distance-mm and --mm-per-px{hint}")


def _clip_roi(roi: tuple[int, int, int, int], size: tuple[int, int]) -> tuple[int, int, int, int]:
    x, y, w, h = (int(v) for v in roi)
    x0, y0 = max(0, x), max(0, y)
    x1, y1 = min(size[0], x + w), min(size[1], y + h)
    if x1 - x0 < 8 or y1 - y0 < 8:
        raise ValueError(f"region of interest {roi} lies outside the {size[0]}x{size[1]} frame")
    return x0, y0, x1 - x0, y1 - y0


def chunk_length(source: FrameSource, quality: LaserQuality) -> int:
    """Frames per chunk: ``chunk_s`` of video, shortened so that a short clip still has
    ``MIN_CHUNKS`` chunks to follow a wandering centre with (:mod:`labkit.vision.laser.wander`); at
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


def line_width(traces: list[TracePoints]) -> float:
    """Median line width of the chunks' traces (NaN without any)."""
    widths = [t.line_width_px for t in traces if len(t.points)]
    return float(np.median(widths)) if widths else math.nan


class _Worker:
    """One worker thread running tasks in order (trace extraction, the first half's
    classification) while the main thread accumulates frames: a ``ThreadPoolExecutor`` with one
    worker, created at the first task, after the first chunk, so that ``concurrent.futures`` and
    the ``logging`` it imports (6 ms) load while frames decode, not before the first frame."""

    def __init__(self) -> None:
        self._pool: ThreadPoolExecutor | None = None

    def submit(self, fn: Callable, *args) -> Future:
        if self._pool is None:
            from concurrent.futures import ThreadPoolExecutor

            self._pool = ThreadPoolExecutor(max_workers=1)
        return self._pool.submit(fn, *args)

    def __enter__(self) -> _Worker:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)


def _load_fit_side():
    """The fit side's module (imported on first use; see ``_FIT_SIDE``)."""
    from labkit.vision.laser import pattern as laser_pattern

    return laser_pattern


def _preload_fit_side() -> None:
    """:func:`_load_fit_side` in a background thread; a failure is left to the main thread's own
    import to report (a thread's traceback would reach the user)."""
    try:
        _load_fit_side()
    except Exception:  # noqa: BLE001 - reported by the import that needs the module
        pass


def _preliminary(gathered: GatheredTrace, chunks: int, fps: float) -> Classification | None:
    """:func:`labkit.vision.laser.pattern.preliminary` (in the worker, while later frames decode)."""
    return _load_fit_side().preliminary(gathered, chunks, fps)


def analyse_laser(path: str, screen_distance_mm: float | None = None, mm_per_px: float | None = None,
                  quality: LaserQuality | None = None, on_frame: FrameHook | None = None,
                  on_trace: Callable[[np.ndarray], None] | None = None,
                  on_progress: Callable[[int, int], None] | None = None) -> LaserResult:
    """Analyse a laser-trace video or long-exposure photo; returns the ``labkit analyse laser``
    result (its JSON: ``.to_json()``).

    ``on_frame(index, t_s, bgr)`` is called for every analysed frame (live streams hook in here;
    the frame buffer is reused, copy it to keep it). ``on_progress(frames_read, frame_count)``
    after each time chunk (``frame_count`` as the file says; 0 if unknown). ``on_trace(image)``
    gets the accumulated trace of the whole clip in a full frame (for :mod:`labkit.vision.laser.overlay`).
    Raises :class:`VideoError` for unusable input; a usable file without a trace gives
    ``pattern.type == "none"`` with a reason.
    """
    quality = quality or LaserQuality()
    t_start = time.perf_counter()
    source = open_frames(path)
    fps = source.fps or 0.0
    per_chunk = chunk_length(source, quality)
    expected = math.ceil(source.frame_count / per_chunk) if source.frame_count > 0 else 0
    with _Worker() as pool:  # trace extraction overlaps decoding
        futures: dict[int, Future] = {}
        histograms: list[Future] = []
        tracker = TraceTracker(max(source.size), quality.subpixel)  # one worker: chunks in order
        done: list[Chunk] = []
        prior: dict[str, Future] = {}
        gathered = GatheredTrace(fps)  # filled by the worker, chunk after chunk

        def extracted(c: Chunk) -> TracePoints:
            trace = tracker.extract(c)
            gathered.add(c, trace)
            return trace

        def extract(c: Chunk) -> None:
            if not done:  # the fit side loads while frames decode, not before the first frame
                threading.Thread(target=_preload_fit_side, name="labkit-fit-import", daemon=True).start()
            futures[id(c)] = pool.submit(extracted, c)
            histograms.append(pool.submit(grey_histogram, c.image))
            done.append(c)
            if on_progress is not None:
                on_progress(c.last + 1, max(source.frame_count, 0))
            if expected >= 4 and len(done) == expected // 2:
                # classify the first half while the second half decodes; the end only refines
                prior["fit"] = pool.submit(_preliminary, gathered, len(done), fps)

        probe = FramePathProbe(_clip_roi(quality.roi, source.size) if quality.roi is not None else None,
                               max(source.size))
        chunks = accumulate(source, quality, on_frame, on_chunk=extract, probe=probe)
        t_frames = time.perf_counter()
        scene = scene_measures([c.image for c in chunks], source.levels[0])  # while the last trace is found
        check_exposure(sum(h.result() for h in histograms), source.path, source.levels)
        traces = [futures[id(c)].result() for c in chunks]
        preliminary = prior["fit"].result() if "fit" in prior else None
    points, weights, times, gathered_band, peak, noise = gathered.result()
    band: tuple[np.ndarray, np.ndarray, np.ndarray | None] | None = gathered_band
    if on_trace is not None:
        from labkit.vision.laser.overlay import accumulated_trace

        on_trace(accumulated_trace(chunks, source.size))
    qual = {"frames_analysed": len(range(0, source.frames_read, quality.stride)),
            "stride": quality.stride, "roi": list(chunks[-1].offset) + list(chunks[-1].image.shape[1::-1]),
            "subpixel": quality.subpixel, "chunks": len(chunks), "trace_points": int(len(points)),
            "peak_level": peak, "noise_level": noise, "truncated": source.truncated,
            "chunks_searched_near_previous_trace": tracker.cropped,
            **_frame_path(chunks, probe)}
    fit_side = _load_fit_side()
    no_trace = fit_side.unreadable(points)
    if no_trace is not None:
        pattern, verdict = no_trace
        tilt = None
        qual = {**verdict, **qual}
    else:
        drift = bool(len(chunks) > 1 and fps)
        if band is not None and not drift:
            band = (band[0], band[1], None)
        middle = (source.frames_read - 1) / (2 * fps) if fps else None
        pattern, diag = fit_side.read_pattern(points, weights, times, drift, band, preliminary, middle,
                                              line_width(traces), tuple(source.size))
        qual = {**{k: diag[k] for k in ("verdict", "reasons", "checks")}, **qual, **diag}
        tilt = None
        if screen_distance_mm and mm_per_px:
            major, minor = pattern["semi_axes_px"]
            tilt = TiltAngles(tilt_from_semi_axis(major, mm_per_px, screen_distance_mm),
                              tilt_from_semi_axis(minor, mm_per_px, screen_distance_mm))
            doubt = tilt_geometry_doubt(major, mm_per_px, screen_distance_mm)
            if doubt is not None:
                verdict = Verdict.from_json(qual)
                verdict.doubt(doubt, "tilt_geometry")
                qual = {**qual, **verdict.as_json()}
    qual = strobe_scene_verdict(qual, *scene)
    qual["settings"] = asdict(quality)
    qual["elapsed_s"] = time.perf_counter() - t_start
    qual["fit_s"] = time.perf_counter() - t_frames  # work left after the last frame: mostly the fit
    return LaserResult(source=source.path, frames=source.frames_read, fps=fps, size=list(source.size),
                       pattern=LaserPattern.from_json(pattern), tilt_rad=tilt,
                       quality=QualityReport.from_json(qual))
