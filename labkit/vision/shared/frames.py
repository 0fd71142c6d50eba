"""Frame sources: a video in any container OpenCV reads, or a single (long-exposure) photo.

Every problem with the input is a :class:`labkit.errors.VideoError` naming the file and the problem
(missing, a directory, unreadable, no frames). A video that ends before its advertised frame count
is reported through :attr:`FrameSource.truncated` after reading.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from labkit.errors import VideoError

LumaChooser = Callable[[list[np.ndarray]], bool]
HELD_FRAMES = 32  # luma planes decoded while the colour probe runs (~30 MB at 1280x720)
PHOTO_SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".webp"}


def read_strided(cap: cv2.VideoCapture, position: list[int], stride: int,
                 reuse: bool) -> Iterator[tuple[int, np.ndarray]]:
    """Yield ``(index, frame)`` for every ``stride``-th frame of ``cap`` from ``position[0]`` on,
    only grabbing (not decoding) the frames between. ``position[0]`` always holds the index of
    the next frame, also when the consumer stops early, so callers can report frames read.
    With ``reuse`` the same buffer is decoded into each time: copy a frame to keep it."""
    buf = None
    while True:
        index = position[0]
        if index % stride:
            if not cap.grab():
                return
        else:
            ok, frame = cap.read(buf) if reuse else cap.read()
            if not ok:
                return
            buf = frame if reuse else None
            yield index, frame
        position[0] = index + 1


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
    levels: tuple[float, float] = (0.0, 255.0)  # grey levels of black and white in the frames yielded
    luma_chosen: bool | None = None  # what ``choose_luma`` decided (None: not asked)

    def frames(self, stride: int = 1, prefetch: int = 0, luma: bool = False,
               choose_luma: LumaChooser | None = None, probe: int = 8) -> Iterator[tuple[int, np.ndarray]]:
        """Yield ``(index, bgr_frame)`` for every ``stride``-th frame; skipped frames are only grabbed
        (demuxed and decoded, not converted), which is cheaper than reading them.

        ``luma=True`` yields the decoder's own luma plane (H, W) instead, skipping the YUV -> BGR
        conversion (~15 % of the decode cost at 720p) when the codec delivers planar YUV
        (mp4v, MJPG, VP9, H.264 ...); otherwise, and for photos, it yields BGR frames as usual.

        ``prefetch > 0`` decodes in a background thread up to that many frames ahead (OpenCV
        releases the GIL while decoding, so decoding overlaps the caller's work); every frame is
        then a fresh array. Without it the same buffer is reused: copy a frame to keep it.

        ``luma=True`` with ``choose_luma``: before decoding, ``choose_luma`` gets the first
        ``probe`` consecutive frames as BGR and luma planes are yielded only if it returns True
        (:attr:`luma_chosen` records the answer); without a luma plane it is not called."""
        if self._photo is not None:
            self.frames_read = 1
            yield 0, self._photo
            return
        if prefetch > 0:
            yield from self._prefetched(stride, prefetch, luma, choose_luma, probe)
        else:
            yield from self._decode(stride, reuse=True, luma=luma, choose_luma=choose_luma, probe=probe)
        if self.frames_read == 0:
            raise VideoError(self.path, "no frame could be decoded (empty or corrupt video)")
        if self.frame_count > 0 and self.frames_read < self.frame_count - 1:
            self.truncated = (f"decoded {self.frames_read} of {self.frame_count} advertised frames "
                              "(truncated file?)")

    def _video(self) -> cv2.VideoCapture:
        """The open capture (a video's source has one; a photo's yields its image before any
        decoding)."""
        if self._cap is None:
            raise VideoError(self.path, "not an opened video")
        return self._cap

    def _decode(self, stride: int, reuse: bool, luma: bool = False, choose_luma: LumaChooser | None = None,
                probe: int = 8) -> Iterator[tuple[int, np.ndarray]]:
        if luma and choose_luma is not None and self._video().getBackendName() == "FFMPEG":
            yield from self._decode_auto(stride, reuse, choose_luma, probe)
            return
        cap, position = self._video(), [0]
        luma = luma and self._luma_plane_available()
        level = cv2.utils.logging.getLogLevel()
        if luma:
            cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
            # FFMPEG warns on every unconverted planar-YUV frame; that is what we asked for
            cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
        try:
            yield from read_strided(cap, position, stride, reuse)
        finally:
            if luma:
                cv2.utils.logging.setLogLevel(level)
            cap.release()
            self.frames_read = position[0]

    def _decode_auto(self, stride: int, reuse: bool, choose_luma: LumaChooser,
                     probe: int) -> Iterator[tuple[int, np.ndarray]]:
        """Luma or colour chosen by ``choose_luma``, without waiting for it: the main reader
        decodes the luma plane at once while a converting reader decodes BGR frames and a judge
        thread decides (OpenCV releases the GIL). If ``choose_luma`` has a ``luma_is_ample``
        method, the judge first gives it the first ``probe`` luma planes the main reader has
        decoded anyway: when they carry the trace clearly, luma is chosen after one BGR frame
        (needed for the planes' grey levels). Otherwise the converting reader decodes the first
        ``probe`` BGR frames for ``choose_luma``. Luma planes decoded meanwhile are held back (at
        most ``HELD_FRAMES``) and yielded if luma is chosen; otherwise (colour chosen, or no
        planar luma from this codec) they are dropped and the converting reader, already some
        frames in, carries on as the colour source."""
        cap, converted = self._video(), cv2.VideoCapture(self.path, cv2.CAP_FFMPEG)
        head: list[np.ndarray] = []
        held: list[tuple[int, np.ndarray]] = []
        plane_ok, planes_ready = threading.Event(), threading.Event()
        verdict: dict[str, bool] = {}
        ample = getattr(choose_luma, "luma_is_ample", None)

        def read_head(n: int) -> None:
            while len(head) < n:
                ok, frame = converted.read()
                if not ok:
                    verdict["converted_ended"] = True
                    return
                head.append(frame)

        def judge() -> None:
            read_head(1 if ample is not None else probe)
            plane_ok.wait()
            if not (verdict["plane"] and head):
                return
            if ample is not None:
                planes_ready.wait()
                if ample([frame for _, frame in held[:probe]]):
                    verdict["luma"] = True
                    return
                read_head(probe)
            verdict["luma"] = bool(choose_luma(head))

        level = cv2.utils.logging.getLogLevel()
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)  # unconverted YUV warnings
        cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
        judge_thread = threading.Thread(target=judge, name="labkit-frame-path", daemon=True)
        judge_thread.start()
        position: list[int] = [0]
        first: np.ndarray | None = None
        try:
            try:
                while judge_thread.is_alive() and len(held) < HELD_FRAMES:
                    index = position[0]
                    if index % stride:
                        if not cap.grab():
                            break
                    else:
                        ok, frame = cap.read()
                        if not ok:
                            break
                        if first is None:
                            w, h = self.size
                            first = frame
                            verdict["plane"] = frame.shape == (h, w) and frame.dtype == np.uint8
                            plane_ok.set()
                            if not verdict["plane"]:
                                break
                        held.append((index, frame))
                        if len(held) == probe:
                            planes_ready.set()
                    position[0] = index + 1
            finally:
                verdict.setdefault("plane", False)
                plane_ok.set()
                planes_ready.set()
                judge_thread.join()
            luma = verdict["plane"] and verdict.get("luma", False)
            if verdict["plane"] and head and first is not None:   # a plane was seen: first is it
                self.luma_chosen = luma
                self._set_levels(first, head[0])
            if luma:
                yield from held
                held.clear()
                yield from read_strided(cap, position, stride, reuse)
            else:
                held.clear()
                cap.release()
                self.levels = (0.0, 255.0)
                position[0] = 0
                for index, frame in enumerate(head):
                    if index % stride == 0:
                        yield index, frame
                    position[0] = index + 1
                if not verdict.get("converted_ended"):
                    yield from read_strided(converted, position, stride, reuse)
        finally:
            cv2.utils.logging.setLogLevel(level)
            cap.release()
            converted.release()
            self.frames_read = position[0]

    def _set_levels(self, plane: np.ndarray, bgr: np.ndarray) -> None:
        """:attr:`levels` from a luma plane and the same frame converted to BGR: studio range
        (16, 235) or full range (0, 255), whichever maps the converted luma onto the plane better."""
        y = plane[::4, ::4].astype(np.float32)
        gray = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)[::4, ::4].astype(np.float32)
        ranges = [(0.0, 255.0), (16.0, 235.0)]
        errors = [float(np.mean(np.abs(y - (lo + gray * (hi - lo) / 255.0)))) for lo, hi in ranges]
        self.levels = ranges[int(np.argmin(errors))]

    def _luma_plane_available(self) -> bool:
        """Whether this file's decoder hands out a planar luma plane (H, W) when conversion is off,
        checked on the first frame (packed or RGB pixel formats fail it). Also sets
        :attr:`levels` from that frame (:meth:`_set_levels`). A reader of its own decodes the
        first frame in colour: the main reader's output format is fixed by its first frame, and
        switching CAP_PROP_CONVERT_RGB mid-stream yields packed BGR bytes in a luma-shaped array."""
        if self._cap is None or self._cap.getBackendName() != "FFMPEG":
            return False
        level = cv2.utils.logging.getLogLevel()
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
        plane = cv2.VideoCapture(self.path, cv2.CAP_FFMPEG)
        converted = cv2.VideoCapture(self.path, cv2.CAP_FFMPEG)
        try:
            plane.set(cv2.CAP_PROP_CONVERT_RGB, 0)
            ok, first = plane.read()
            ok_bgr, bgr = converted.read()
        finally:
            plane.release()
            converted.release()
            cv2.utils.logging.setLogLevel(level)
        w, h = self.size
        if not (ok and ok_bgr and first.shape == (h, w) and first.dtype == np.uint8):
            return False
        self._set_levels(first, bgr)
        return True

    def _prefetched(self, stride: int, depth: int, luma: bool = False, choose_luma: LumaChooser | None = None,
                    probe: int = 8) -> Iterator[tuple[int, np.ndarray]]:
        q: queue.Queue = queue.Queue(maxsize=depth)
        stop = threading.Event()
        done = object()

        def work() -> None:
            try:
                frames = self._decode(stride, reuse=False, luma=luma, choose_luma=choose_luma, probe=probe)
                for item in frames:
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

    def decode_only(self, luma: bool = False) -> int:
        """Read every frame and do nothing else (the benchmark's reference); returns the count."""
        return sum(1 for _ in self.frames(luma=luma))


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
        from labkit.vision.shared.image_size import check_image_pixels

        check_image_pixels(name)  # header only: an image bomb never reaches OpenCV
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
