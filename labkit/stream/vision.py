"""Rerun logging of video analysis (``labkit analyse laser|strobe --rerun SPEC``).

Entity paths (timelines ``frame`` = frame index and ``video_time`` = seconds into the clip):

========================  =========================================================================
entity                     content
========================  =========================================================================
``/video/frame``           the analysed frames, JPEG-encoded (raw images bloat .rrd files ~30x)
``/video/frame/fit``       the fitted circle/ellipse/trochoid, drawn over every frame (static)
``/video/frame/center``    the pattern centre
``/video/pattern``         text: classification, its numbers and the quality verdict, once the analysis ends
``/video/overlay``         laser: the fitted curve over the accumulated trace, with the verdict
                           (the image ``labkit analyse laser --overlay OUT.png`` writes; static)
``/video/trace``           the accumulated trace (per-pixel maximum of the analysed frames, or
                           minimum when the body is darker than the background)
``/video/trace/fit``       the fitted curve over the accumulated trace
========================  =========================================================================

OpenCV puts pixel centres at integers, rerun at +0.5 (docs/explanation/rerun-notes.md#pixel-centres), so every
pixel coordinate is shifted by +0.5 when logged.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from labkit.stream.core import RerunSpec, open_stream

PIXEL_CENTRE = 0.5


def vision_blueprint() -> Any:
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                rrb.Spatial2DView(origin="/video/trace", name="accumulated trace and fitted curve"),
                rrb.Spatial2DView(origin="/video/frame", name="frames and fit"),
                rrb.Spatial2DView(origin="/video/overlay", name="overlay with the verdict"),
            ),
            rrb.TextLogView(origin="/video/pattern", name="pattern"),
            row_shares=[5, 1],
        ),
        collapse_panels=True,
    )


def pattern_curve(pattern: dict[str, Any], samples: int = 720) -> np.ndarray | None:
    """Points (N, 2) of the fitted pattern of a ``labkit analyse`` JSON, in OpenCV pixels."""
    from labkit.vision.laser.overlay import pattern_curve as curve

    return curve(pattern, samples)


class VisionStream:
    """The object ``labkit analyse`` feeds: ``frame(index, t_s, bgr)``, ``result(dict)``, ``close()``."""

    def __init__(self, rec: Any, every: int = 1, jpeg_quality: int = 80) -> None:
        import rerun as rr

        self.rr, self.rec = rr, rec
        self.every = max(1, int(every))
        self.jpeg_quality = jpeg_quality
        self.frames_logged = 0
        self.trace: np.ndarray | None = None   # per-pixel maximum of the analysed frames
        self.trace_dark: np.ndarray | None = None   # per-pixel minimum (a dark body on light)
        self.last_time: tuple[int, float] | None = None

    def frame(self, index: int, t_s: float, bgr: np.ndarray) -> None:
        if index % self.every:
            return
        import cv2

        ok, encoded = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
        if not ok:
            return
        self.rec.set_time("frame", sequence=int(index))
        self.rec.set_time("video_time", duration=float(t_s))
        image = self.rr.EncodedImage(contents=encoded.tobytes(), media_type="image/jpeg")
        self.rec.log("/video/frame", image)
        self.frames_logged += 1
        self.last_time = (int(index), float(t_s))
        fresh = self.trace is None or self.trace.shape != bgr.shape
        self.trace = bgr.copy() if fresh else np.maximum(self.trace, bgr)
        self.trace_dark = bgr.copy() if fresh else np.minimum(self.trace_dark, bgr)

    def result(self, result: Mapping[str, Any]) -> None:
        pattern = result.get("pattern") or result.get("point_pattern") or {}
        curve = pattern_curve(pattern)
        self._log_trace(curve)
        if curve is not None:
            strip = self.rr.LineStrips2D([curve + PIXEL_CENTRE], colors=[[0, 255, 0]])
            self.rec.log("/video/frame/fit", strip, static=True)
            center = np.asarray(pattern["center_px"], dtype=float) + PIXEL_CENTRE
            self.rec.log("/video/frame/center", self.rr.Points2D([center], radii=3, colors=[[255, 0, 0]]),
                         static=True)
        if self.last_time is not None:   # on the timelines, so the text log view lists it
            self.rec.set_time("frame", sequence=self.last_time[0])
            self.rec.set_time("video_time", duration=self.last_time[1])
        self.rec.log("/video/pattern", self.rr.TextLog(describe(result), level="INFO"),
                     static=self.last_time is None)

    def _log_trace(self, curve: np.ndarray | None) -> None:
        """The accumulated trace with the fitted curve over it (static: the whole clip)."""
        if self.trace is None or self.trace_dark is None:
            return
        import cv2

        background = float(np.median(self.trace))
        bright = float(self.trace.max()) - background
        dark = background - float(self.trace_dark.min())
        trace = self.trace if bright >= dark else self.trace_dark   # a bright spot, or a dark body
        ok, encoded = cv2.imencode(".jpg", trace, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
        if ok:
            self.rec.log("/video/trace", self.rr.EncodedImage(contents=encoded.tobytes(),
                                                               media_type="image/jpeg"), static=True)
        if curve is not None:
            strip = self.rr.LineStrips2D([curve + PIXEL_CENTRE], colors=[[0, 255, 0]])
            self.rec.log("/video/trace/fit", strip, static=True)

    def overlay(self, bgr: np.ndarray) -> None:
        """Log the overlay image (:func:`labkit.vision.laser.overlay.draw_overlay`) as a static PNG."""
        import cv2

        ok, encoded = cv2.imencode(".png", bgr)
        if ok:
            image = self.rr.EncodedImage(contents=encoded.tobytes(), media_type="image/png")
            self.rec.log("/video/overlay", image, static=True)

    def close(self) -> None:
        try:
            self.rec.flush()
        finally:
            self.rec.disconnect()


def describe(result: Mapping[str, Any]) -> str:
    """One line about the analysis for the viewer's log."""
    pattern = result.get("pattern") or result.get("point_pattern") or {}
    kind = pattern.get("type", "none")
    if kind == "none":
        return f"{result.get('source')}: no pattern ({pattern.get('reason', 'no usable trace')})"
    parts = [f"{result.get('source')}: {kind}"]
    if pattern.get("ellipticity") is not None:
        parts.append(f"ellipticity {pattern['ellipticity']:.3f}")
    if pattern.get("loops") and kind not in ("circle", "ellipse"):
        parts.append(f"{pattern['loops']} loops")
    if result.get("tilt_amplitude_rad") is not None:
        parts.append(f"tilt amplitude {result['tilt_amplitude_rad']:.4f} rad")
    quality = result.get("quality") or {}
    if quality.get("verdict"):
        from labkit.vision.shared.verdict import QualityReport, in_words

        parts.append(in_words(QualityReport.from_json(quality)))
    return ", ".join(parts)


def open_vision_stream(spec: RerunSpec | str, kind: str, every: int = 1) -> VisionStream:
    rec = open_stream(spec, f"labkit-analyse-{kind}", blueprint=vision_blueprint(),
                      fallback_file=f"analyse-{kind}.rrd")
    return VisionStream(rec, every=every)
