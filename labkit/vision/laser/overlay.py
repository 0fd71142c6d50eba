"""The fitted pattern drawn over the accumulated trace (``labkit analyse laser --overlay OUT.png``
and the rerun stream's ``/video/overlay``): what a reviewer looks at to judge a result.

The trace (per-pixel maximum over the whole clip) is shown dimmed in grey; the fitted curve in
green (the pattern at the reported centre, i.e. at the middle of the recording), its centre as a
red cross, and the verdict with its first reason written in the top-left corner (green ok,
amber doubtful, red failed).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from labkit.vision.laser.result import LaserResult
from labkit.vision.shared.curves import Pattern

VERDICT_BGR = {"ok": (80, 200, 60), "doubtful": (0, 170, 255), "failed": (40, 40, 230)}
CURVE_BGR = (60, 230, 60)
CENTRE_BGR = (40, 40, 255)


def pattern_curve(pattern: dict, samples: int = 2000) -> np.ndarray | None:
    """Points (N, 2) of the fitted pattern of a ``labkit analyse laser`` JSON ``pattern`` object
    (OpenCV pixel coordinates); None for ``none``."""
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


def _label(result: LaserResult) -> list[str]:
    p, q = result.pattern, result.quality
    head = p.type if p.type in ("none", "circle", "ellipse") else f"{p.type}, {p.loops} loops"
    lines = [f"{head}: {q.verdict}"]
    lines += [r if len(r) <= 90 else r[:87] + "..." for r in q.reasons[:2]]
    return lines


def draw_overlay(trace: np.ndarray, result: LaserResult) -> np.ndarray:
    """BGR image: ``trace`` (grey or BGR, full frame) dimmed, the fitted curve, its centre and the
    verdict of ``result`` (a ``labkit analyse laser`` result)."""
    grey = trace if trace.ndim == 2 else cv2.cvtColor(trace, cv2.COLOR_BGR2GRAY)
    grey = cv2.normalize(grey, None, 0, 200, cv2.NORM_MINMAX)  # type: ignore[call-overload]  # stubs: dst None allocates
    image = cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
    h, w = grey.shape
    thick = max(1, round(max(w, h) / 640))
    shift = 4  # sub-pixel drawing: coordinates in 1/16 px
    curve = pattern_curve(result.pattern.to_json())
    if curve is not None and result.pattern.center_px is not None:
        pts = np.round(curve * (1 << shift)).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(image, [pts], True, CURVE_BGR, thick, cv2.LINE_AA, shift)
        cx, cy = result.pattern.center_px
        size = 6 * thick
        cv2.drawMarker(image, (round(cx), round(cy)), CENTRE_BGR, cv2.MARKER_CROSS, size, thick, cv2.LINE_AA)
    colour = VERDICT_BGR.get(result.verdict, (255, 255, 255))
    scale = 0.45 * max(1.0, max(w, h) / 640)
    y = round(22 * scale / 0.45)
    for line in _label(result):
        (tw, th), base = cv2.getTextSize(line, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
        cv2.rectangle(image, (4, y - th - 4), (12 + tw, y + base), (0, 0, 0), cv2.FILLED)
        cv2.putText(image, line, (8, y), cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thick, cv2.LINE_AA)
        y += round(20 * scale / 0.45)
    return image


def accumulated_trace(chunks: list, size: tuple[int, int]) -> np.ndarray:
    """The per-pixel maximum of every chunk's accumulation, placed in a full frame of ``size``
    (w, h); grey if the chunks are luma planes, else BGR."""
    w, h = size
    first = chunks[0].image
    full = np.zeros((h, w) + first.shape[2:], first.dtype)
    for c in chunks:
        x, y = c.offset
        ch, cw = c.image.shape[:2]
        cv2.max(full[y:y + ch, x:x + cw], c.image, dst=full[y:y + ch, x:x + cw])
    return full
