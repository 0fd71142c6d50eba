"""Rerun logging of video analysis (``labkit analyse laser|strobe --rerun SPEC``).

Entity paths (timelines ``frame`` = frame index and ``video_time`` = seconds into the clip):

========================  =========================================================================
entity                     content
========================  =========================================================================
``/video/frame``           the analysed frames, JPEG-encoded (raw images bloat .rrd files ~30x)
``/video/frame/fit``       the fitted circle/ellipse/trochoid, drawn over every frame (static)
``/video/frame/center``    the pattern centre
``/video/pattern``         text: classification and its numbers, once the analysis ends
========================  =========================================================================

OpenCV puts pixel centres at integers, rerun at +0.5 (docs/design/rerun-notes.md#pixel-centres), so every
pixel coordinate is shifted by +0.5 when logged.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from labkit.stream.core import RerunSpec, open_stream

PIXEL_CENTRE = 0.5


def vision_blueprint() -> Any:
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Spatial2DView(origin="/video/frame", name="frames and fit"),
            rrb.TextLogView(origin="/video/pattern", name="pattern"),
            row_shares=[5, 1],
        ),
        collapse_panels=True,
    )


def pattern_curve(pattern: dict[str, Any], samples: int = 720) -> np.ndarray | None:
    """Points (N, 2) of the fitted pattern of a ``labkit analyse`` JSON, in OpenCV pixels."""
    from labkit.vision.curves import Pattern

    kind = pattern.get("type")
    if kind in (None, "none") or pattern.get("center_px") is None:
        return None
    center = tuple(pattern["center_px"])
    if kind in ("circle", "ellipse"):
        shape = Pattern(kind, center, math.radians(pattern.get("rotation_deg") or 0.0),
                        tuple(pattern["semi_axes_px"]))
    else:
        troch = pattern.get("trochoid") or {}
        shape = Pattern(kind, center, math.radians(troch.get("rotation_deg") or 0.0),
                        scale=float(troch["scale_px"]), b=float(troch["b"]), loops=int(pattern["loops"]))
    return shape.points(np.linspace(0.0, 2.0 * math.pi, samples))


class VisionStream:
    """The object ``labkit analyse`` feeds: ``frame(index, t_s, bgr)``, ``result(dict)``, ``close()``."""

    def __init__(self, rec: Any, every: int = 1, jpeg_quality: int = 80) -> None:
        import rerun as rr

        self.rr, self.rec = rr, rec
        self.every = max(1, int(every))
        self.jpeg_quality = jpeg_quality
        self.frames_logged = 0

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

    def result(self, result: dict[str, Any]) -> None:
        pattern = result.get("pattern") or result.get("point_pattern") or {}
        curve = pattern_curve(pattern)
        if curve is not None:
            strip = self.rr.LineStrips2D([curve + PIXEL_CENTRE], colors=[[0, 255, 0]])
            self.rec.log("/video/frame/fit", strip, static=True)
            center = np.asarray(pattern["center_px"], dtype=float) + PIXEL_CENTRE
            self.rec.log("/video/frame/center", self.rr.Points2D([center], radii=3, colors=[[255, 0, 0]]),
                         static=True)
        self.rec.log("/video/pattern", self.rr.TextLog(describe(result), level="INFO"), static=True)

    def close(self) -> None:
        try:
            self.rec.flush()
        finally:
            self.rec.disconnect()


def describe(result: dict[str, Any]) -> str:
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
    return ", ".join(parts)


def open_vision_stream(spec: RerunSpec | str, kind: str, every: int = 1) -> VisionStream:
    rec = open_stream(spec, f"labkit-analyse-{kind}", blueprint=vision_blueprint(),
                      fallback_file=f"analyse-{kind}.rrd")
    return VisionStream(rec, every=every)
