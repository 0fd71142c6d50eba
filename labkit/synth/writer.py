"""Write synthetic frames as a video (mp4v / MJPG / any OpenCV fourcc) or a photo, with the ground
truth as JSON beside it (``clip.mp4`` -> ``clip.truth.json``)."""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path

import cv2
import numpy as np

from labkit.errors import VideoError

PHOTO_SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp"}
VIDEO_SUFFIXES = {".mp4", ".avi", ".mkv", ".mov", ".m4v"}


def truth_path(path: str | Path) -> Path:
    """Where the ground truth of a clip lives: same stem, ``.truth.json``."""
    p = Path(path)
    return p.with_name(p.stem + ".truth.json")


def _photo(frames: Iterable[np.ndarray]) -> np.ndarray:
    """A long-exposure photo: the brightest value per pixel over all frames (the trace sum)."""
    acc = None
    for f in frames:
        acc = f.copy() if acc is None else np.maximum(acc, f)
    if acc is None:
        raise ValueError("no frames to write")
    return acc


def write_clip(path: str | Path, frames: Iterable[np.ndarray], fps: float, codec: str,
               truth: dict | None) -> Path:
    """Write frames to ``path`` (a photo when the suffix is an image type) and ``truth`` beside it.

    Raises :class:`VideoError` if OpenCV cannot open a writer for this codec and container or a
    frame is rejected."""
    p = Path(path)
    if p.suffix.lower() not in PHOTO_SUFFIXES | VIDEO_SUFFIXES:
        kinds = ", ".join(sorted(VIDEO_SUFFIXES | PHOTO_SUFFIXES))
        raise VideoError(str(p), f"unknown output type {p.suffix or '(none)'}; use one of {kinds}")
    p.parent.mkdir(parents=True, exist_ok=True)
    if p.suffix.lower() in PHOTO_SUFFIXES:
        if not cv2.imwrite(str(p), _photo(frames)):
            raise VideoError(str(p), "OpenCV could not write this image type")
    else:
        writer = None
        try:
            for f in frames:
                if writer is None:
                    h, w = f.shape[:2]
                    writer = cv2.VideoWriter(str(p), cv2.VideoWriter_fourcc(*codec[:4].ljust(4)), fps,
                                             (w, h))
                    if not writer.isOpened():
                        raise VideoError(str(p), f"OpenCV cannot write fourcc {codec!r} into "
                                                 f"{p.suffix or 'this container'} (try mp4v/.mp4, MJPG/.avi)")
                if writer.write(f) is False:
                    raise VideoError(str(p), "OpenCV rejected a frame (size mismatch)")
        finally:
            if writer is not None:
                writer.release()
    if truth is not None:
        truth_path(p).write_text(json.dumps(truth, indent=1) + "\n")
    return p
