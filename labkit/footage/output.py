"""Write footage with OpenCV (mp4v video, JPEG photo) and its ground truth beside it as
``NAME.truth.json``."""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path

import cv2
import numpy as np

PHOTO_SUFFIXES = (".jpg", ".jpeg", ".png")


def truth_path(path: str | Path) -> Path:
    """``clip.mp4`` -> ``clip.truth.json``."""
    p = Path(path)
    return p.with_name(p.stem + ".truth.json")


def write_footage(path: str | Path, frames: Iterable[np.ndarray], fps: float, truth: dict,
                  jpeg_quality: int = 92) -> Path:
    """Write frames as an mp4v video (any other suffix than a photo's) or the single frame as a
    photo (.jpg/.png), then the truth JSON; returns the footage's path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix.lower() in PHOTO_SUFFIXES:
        (image,) = list(frames)
        params = [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)] if path.suffix.lower() != ".png" else []
        if not cv2.imwrite(str(path), image, params):
            raise OSError(f"{path}: OpenCV could not write the photo")
    else:
        writer = None
        try:
            for frame in frames:
                if writer is None:
                    h, w = frame.shape[:2]
                    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (w, h))
                    if not writer.isOpened():
                        raise OSError(f"{path}: OpenCV could not open an mp4v writer")
                writer.write(frame)
        finally:
            if writer is not None:
                writer.release()
    truth_path(path).write_text(json.dumps(truth, indent=1, default=_plain))
    return path


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, complex):
        return [value.real, value.imag]
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
