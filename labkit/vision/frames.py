"""Frame sources: a video in any container OpenCV reads, or a single (long-exposure) photo.

Every problem with the input is a :class:`labkit.errors.VideoError` naming the file and the problem
(missing, a directory, unreadable, no frames). A video that ends before its advertised frame count
is reported through :attr:`FrameSource.truncated` after reading.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from labkit.errors import VideoError

PHOTO_SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".webp"}


@dataclass
class FrameSource:
    """An opened video or photo. Iterate :meth:`frames` once."""

    path: str
    is_photo: bool
    fps: float
    size: tuple[int, int]  # width, height
    frame_count: int  # advertised (video) or 1 (photo); 0 if unknown
    _cap: cv2.VideoCapture | None = None
    _photo: np.ndarray | None = None
    frames_read: int = 0
    truncated: str | None = None

    def frames(self, stride: int = 1, prefetch: int = 0) -> Iterator[tuple[int, np.ndarray]]:
        """Yield ``(index, bgr_frame)`` for every ``stride``-th frame; skipped frames are only grabbed
        (demuxed and decoded, not converted), which is cheaper than reading them.

        ``prefetch > 0`` decodes in a background thread up to that many frames ahead (OpenCV
        releases the GIL while decoding, so decoding overlaps the caller's work); every frame is
        then a fresh array. Without it the same buffer is reused: copy a frame to keep it."""
        if self._photo is not None:
            self.frames_read = 1
            yield 0, self._photo
            return
        if prefetch > 0:
            yield from self._prefetched(stride, prefetch)
        else:
            yield from self._decode(stride, reuse=True)
        if self.frames_read == 0:
            raise VideoError(self.path, "no frame could be decoded (empty or corrupt video)")
        if self.frame_count > 0 and self.frames_read < self.frame_count - 1:
            self.truncated = (f"decoded {self.frames_read} of {self.frame_count} advertised frames "
                              "(truncated file?)")

    def _decode(self, stride: int, reuse: bool) -> Iterator[tuple[int, np.ndarray]]:
        cap, index, buf = self._cap, 0, None
        try:
            while True:
                if index % stride:
                    if not cap.grab():
                        break
                else:
                    ok, frame = cap.read(buf) if reuse else cap.read()
                    if not ok:
                        break
                    buf = frame if reuse else None
                    yield index, frame
                index += 1
        finally:
            cap.release()
            self.frames_read = index

    def _prefetched(self, stride: int, depth: int) -> Iterator[tuple[int, np.ndarray]]:
        q: queue.Queue = queue.Queue(maxsize=depth)
        stop = threading.Event()
        done = object()

        def work() -> None:
            try:
                for item in self._decode(stride, reuse=False):
                    while not stop.is_set():
                        try:
                            q.put(item, timeout=0.1)
                            break
                        except queue.Full:
                            continue
                    if stop.is_set():
                        return
            finally:
                q.put(done)

        thread = threading.Thread(target=work, name="labkit-decode", daemon=True)
        thread.start()
        try:
            while (item := q.get()) is not done:
                yield item
        finally:
            stop.set()
            while thread.is_alive():  # unblock a producer waiting on a full queue
                try:
                    q.get(timeout=0.05)
                except queue.Empty:
                    pass
            thread.join()

    def decode_only(self) -> int:
        """Read every frame and do nothing else (the benchmark's reference); returns the count."""
        return sum(1 for _ in self.frames())


def open_frames(path: str | Path) -> FrameSource:
    """Open a video or a photo for analysis; raises :class:`VideoError` with a reason."""
    p = Path(path)
    name = str(p)
    if not p.exists():
        raise VideoError(name, "no such file")
    if p.is_dir():
        raise VideoError(name, "is a directory, expected a video or photo")
    if p.stat().st_size == 0:
        raise VideoError(name, "file is empty (0 bytes)")
    if p.suffix.lower() in PHOTO_SUFFIXES:
        img = cv2.imread(name, cv2.IMREAD_COLOR)
        if img is None:
            raise VideoError(name, "cannot be read as an image (unknown or corrupt format)")
        h, w = img.shape[:2]
        return FrameSource(name, True, 0.0, (w, h), 1, _photo=img)
    cap = cv2.VideoCapture(name)
    if not cap.isOpened():
        cap.release()
        raise VideoError(name, "cannot be read as a video (unknown container or codec, or truncated)")
    w, h = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
    fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    count = max(0, int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0))
    if w <= 0 or h <= 0:
        cap.release()
        raise VideoError(name, "video has no picture size (no video stream?)")
    return FrameSource(name, False, fps, (w, h), count, _cap=cap)
