"""``labkit analyse strobe --overlay OUT.png``: the measured body over a frame of the clip
(docs/explanation/strobe-analysis.md, *Overlay*).

Drawn over the first frame with a body: the rest axis (grey, through the body's centroid), the
body axis measured in that frame (green, its measured half length either side of the centroid,
the "top" end ringed), the tracked point in every frame (small yellow dots, the trajectory the
``point_pattern`` fits) and in this frame (red ring), a magnified inset of the body when it is
small in the frame, and a caption with the verdict, its first reasons and the fitted amplitudes.
Pure drawing: the analysis hands over the frame and the geometry.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from labkit.errors import VideoError
from labkit.vision.strobe.result import OverlayFrame, StrobeResult

GREEN, GREY, RED, YELLOW, WHITE = (0, 220, 0), (160, 160, 160), (0, 0, 255), (0, 230, 255), (255, 255, 255)
VERDICT_COLOURS = {"ok": (0, 200, 0), "doubtful": (0, 190, 255), "failed": (0, 0, 255)}


def _draw_geometry(img: np.ndarray, drawing: OverlayFrame, origin: np.ndarray, zoom: float,
                   thick: int) -> None:
    def pt(p) -> tuple[int, int]:
        q = (np.asarray(p, float) - origin) * zoom
        return int(round(q[0] * 16)), int(round(q[1] * 16))

    c = np.asarray(drawing.centre, float)
    half = float(drawing.half_length_px)
    rest = np.asarray(drawing.rest_axis, float)
    axis = np.asarray(drawing.axis, float)
    reach = 1.6 * half
    cv2.line(img, pt(c - reach * rest), pt(c + reach * rest), GREY, thick, cv2.LINE_AA, 4)
    cv2.line(img, pt(c - half * axis), pt(c + half * axis), GREEN, thick + 1, cv2.LINE_AA, 4)
    cv2.circle(img, pt(c + half * axis), int(3 * thick) * 16, GREEN, thick, cv2.LINE_AA, 4)  # the top end
    for p in drawing.track:
        cv2.circle(img, pt(p), max(1, thick) * 16, YELLOW, -1, cv2.LINE_AA, 4)
    cv2.circle(img, pt(drawing.point), int(5 * thick) * 16, RED, thick + 1, cv2.LINE_AA, 4)


def _inset(frame: np.ndarray, drawing: OverlayFrame, out: np.ndarray, thick: int) -> None:
    """A magnified view of the body in the bottom-right corner, when the body is small."""
    h, w = out.shape[:2]
    centre = np.asarray(drawing.centre, float)
    track = np.asarray(drawing.track, float)
    reach = float(np.abs(track - centre).max()) if track.size else 0.0
    radius = 1.25 * max(float(drawing.radius_px), reach) + 4
    side = int(0.45 * min(h, w))
    zoom = min(6.0, side / (2 * radius))
    if zoom < 1.5:
        return
    origin = centre - radius
    m = np.array([[zoom, 0, -origin[0] * zoom], [0, zoom, -origin[1] * zoom]], np.float32)
    view = cv2.warpAffine(frame, m, (side, side), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
    _draw_geometry(view, drawing, origin, zoom, thick + 1)
    cv2.putText(view, f"x{zoom:.1f}", (6, side - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.5, RED, 1, cv2.LINE_AA)
    cv2.rectangle(view, (0, 0), (side - 1, side - 1), WHITE, 2)
    out[h - side - 8:h - 8, w - side - 8:w - 8] = view


def draw_strobe_overlay(frame: np.ndarray, result: StrobeResult, drawing: OverlayFrame) -> np.ndarray:
    """The overlay image (BGR). ``drawing``: ``centre``, ``axis`` (unit vector to the top end),
    ``rest_axis``, ``half_length_px``, ``radius_px`` (the body's half diagonal), ``point``,
    ``track`` (points of every frame), in px."""
    frame = frame if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    img = frame.copy()
    h, w = img.shape[:2]
    scale = max(1.0, min(w, h) / 480)
    thick = max(1, int(round(scale)))
    _draw_geometry(img, drawing, np.zeros(2), 1.0, thick)
    _inset(frame, drawing, img, thick)
    q, u = result.quality, result.uncertainty
    lines = [f"{q.verdict.upper()}  {Path(result.source).name}",
             f"tilt {result.tilt_amplitude_rad:.4f} +- {u.tilt_amplitude_rad:.4f} rad   "
             f"lateral {result.lateral_amplitude_px:.2f} +- {u.lateral_amplitude_px:.2f} px",
             f"rest axis {result.body.rest_axis_deg:.1f} deg  {q.evidence['point']}: "
             f"{result.point_pattern.type}"]
    lines += [r[:80] for r in q.reasons[:2]]
    font = 0.45 * scale
    step = int(18 * scale)
    width = max(cv2.getTextSize(t, cv2.FONT_HERSHEY_SIMPLEX, font, thick)[0][0] for t in lines)
    box = img[0:step * len(lines) + 8, 0:min(w, width + 16)]
    box[:] = (box * 0.35).astype(np.uint8)  # darken behind the caption
    for i, text in enumerate(lines):
        colour = VERDICT_COLOURS.get(q.verdict, WHITE) if i == 0 else WHITE
        cv2.putText(img, text, (8, step * (i + 1)), cv2.FONT_HERSHEY_SIMPLEX, font, colour, thick,
                    cv2.LINE_AA)
    return img


def write_strobe_overlay(out: str, frame: np.ndarray, result: StrobeResult, drawing: OverlayFrame) -> Path:
    """Draw and write the overlay PNG; raises :class:`VideoError` naming ``out`` if it cannot."""
    img = draw_strobe_overlay(frame, result, drawing)
    path = Path(out)
    try:
        ok = cv2.imwrite(str(path), img)
    except cv2.error:
        ok = False
    if not ok:
        raise VideoError(out, "cannot write the overlay image (check the folder and the extension, "
                              "e.g. .png)")
    return path
