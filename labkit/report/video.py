"""Contact sheet for a video analysis result (``labkit analyse laser`` JSON).

The result names its ``source`` video or photo and the fitted ``pattern`` (``center_px``,
``semi_axes_px``, ``rotation_deg``, and for trochoids ``trochoid: {a, b, scale_px,
rotation_deg}``, Eq. 6.38). A few frames spread over the clip are drawn with the pattern on
top.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from labkit.errors import VideoError

PHOTO_SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp"}


def sample_frames(path: str | Path, count: int = 8) -> list[tuple[int, np.ndarray]]:
    """``count`` frames spread evenly over a video (or the photo itself), as (index, BGR)."""
    p = Path(path)
    if not p.exists():
        raise VideoError(str(p), "no such file (the video the result was made from)")
    if p.suffix.lower() in PHOTO_SUFFIXES:
        from labkit.vision.shared.image_size import check_image_pixels

        check_image_pixels(p)  # header only: an image bomb never reaches OpenCV
        img = cv2.imread(str(p), cv2.IMREAD_COLOR)
        if img is None:
            raise VideoError(str(p), "cannot be decoded as an image")
        return [(0, img)]
    cap = cv2.VideoCapture(str(p))
    advertised = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    wanted = (set(np.linspace(0, advertised - 1, min(count, advertised)).round().astype(int).tolist())
              if advertised > 0 else None)
    kept: list[tuple[int, np.ndarray]] = []
    try:
        index = 0
        while True:
            if wanted is not None and index not in wanted:
                if not cap.grab():       # skip without decoding into an image
                    break
            else:
                ok, img = cap.read()
                if not ok:
                    break
                kept.append((index, img))
            index += 1
    finally:
        cap.release()
    if not kept:
        raise VideoError(str(p), "no frame could be decoded")
    if wanted is None:   # frame count unknown: every frame was kept, thin out now
        idx = np.unique(np.linspace(0, len(kept) - 1, min(count, len(kept))).round().astype(int))
        kept = [kept[i] for i in idx]
    return kept


def pattern_points(pattern: dict, samples: int = 720) -> np.ndarray | None:
    """Pixel points of the fitted pattern (ellipse, or trochoid of Eq. 6.38), or None."""
    if not pattern or pattern.get("type") in (None, "none") or pattern.get("center_px") is None:
        return None
    cx, cy = pattern["center_px"]
    t = np.linspace(0, 2 * math.pi, samples)
    tro = pattern.get("trochoid")
    if tro:
        a, b, s = float(tro["a"]), float(tro["b"]), float(tro["scale_px"])
        rot = math.radians(float(tro.get("rotation_deg") or 0.0))
        z = np.exp(1j * t) + b * np.exp(1j * (1 + a) / a * t)
        z = s * z * np.exp(1j * rot)
    else:
        major, minor = pattern["semi_axes_px"]
        rot = math.radians(float(pattern.get("rotation_deg") or 0.0))
        z = (major * np.cos(t) + 1j * minor * np.sin(t)) * np.exp(1j * rot)
    return np.column_stack([cx + z.real, cy + z.imag])


def overlay(frame: np.ndarray, pattern: dict) -> np.ndarray:
    img = frame.copy()
    pts = pattern_points(pattern)
    if pts is not None:
        cv2.polylines(img, [np.round(pts).astype(np.int32).reshape(-1, 1, 2)], True, (0, 255, 0), 1,
                      cv2.LINE_AA)
    return img
