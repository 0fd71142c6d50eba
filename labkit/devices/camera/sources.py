"""Live frame sources through OpenCV: a UVC camera (V4L2 backend) and an MJPEG stream over HTTP
(OpenCV's FFmpeg client in raw mode, which hands over each JPEG exactly as the server sent it).

This layer is kept thin on purpose: the V4L2 ioctl path cannot run in CI (no camera and no
v4l2loopback in a container, docs/how-to/film-a-rig.md); everything above it (grab thread, timeouts, drop
counting, cassettes) is shared with the sources CI does exercise (``http://`` on a loopback
server, ``sim://camera``, ``replay://``).

A source's ``read(timeout_s)`` returns a :class:`RawFrame` or raises :class:`SourceStopped`
with what it stopped doing; it never blocks much longer than ``timeout_s``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

from labkit.devices.camera.frames import CameraSettings
from labkit.devices.camera.urls import CameraRequest

JPEG_QUALITY = 90  # frames a camera does not send as JPEG are encoded once, at this quality


class SourceStopped(Exception):
    """The source ended or failed: ``args[0]`` says what it stopped doing (one line)."""


@dataclass(frozen=True)
class RawFrame:
    """What a source hands the grab thread: JPEG bytes, the device's time on the run's clock
    (None if it has none), its sequence number (None if it has none), for replays the recorded
    arrival time and drops, and ``meta`` the source adds (the emulated camera: the model's truth)."""

    payload: bytes
    t_device: float | None = None
    seq: int | None = None
    t_host: float | None = None
    dropped_before: int | None = None
    meta: dict[str, Any] | None = None


def encode_jpeg(image: np.ndarray, quality: int = JPEG_QUALITY) -> bytes:
    """One frame as JPEG bytes (a camera that does not send JPEG is encoded here, once)."""
    import cv2

    ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise SourceStopped(f"could not encode a {image.shape} frame as JPEG")
    return buf.tobytes()


def fourcc_text(value: float) -> str:
    code = int(value)
    text = "".join(chr((code >> (8 * i)) & 0xFF) for i in range(4))
    return text if text.isprintable() and text.strip() else f"0x{code:08x}"


def _payload(data: Any, raw_jpeg: bool) -> bytes:
    import numpy as np

    arr = np.asarray(data)
    if raw_jpeg and arr.ndim <= 2 and (arr.ndim == 1 or arr.shape[0] == 1) and arr.dtype == np.uint8:
        return arr.tobytes()  # the camera's own JPEG: stored as sent
    return encode_jpeg(arr)


class HttpMjpegSource:
    """``http://HOST:PORT/PATH``: OpenCV's FFmpeg client, raw packets (``CAP_PROP_FORMAT = -1``).

    The stream's timestamps are synthetic (OpenCV reports 40 ms steps whatever the rate), so frames
    carry only their arrival time. Open and read timeouts are FFmpeg's own interrupt timeouts."""

    live = True

    def __init__(self, request: CameraRequest) -> None:
        self.request = request
        self.cap: Any = None
        nominal = request.options.get("nominal_fps")
        #: the rate set in the phone's app (URL ``nominal_fps``): the camera counts arrival gaps
        #: against it (an estimate, docs/reference/camera.md); None: a stream's drops are not counted
        self.nominal_fps = float(nominal) if nominal else None

    def open(self, clock: Any) -> CameraSettings:
        import cv2

        ms = int(self.request.timeout_s * 1000)
        # FFmpeg's interrupt warning would repeat, as a second stderr line, the one-line fault
        # the camera raises (process-wide: OpenCV has one log level)
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
        self.cap = cv2.VideoCapture(self.request.target, cv2.CAP_FFMPEG,
                                    [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, ms, cv2.CAP_PROP_READ_TIMEOUT_MSEC, ms])
        if not self.cap.isOpened():
            raise SourceStopped(f"no MJPEG stream could be opened within {self.request.timeout_s:g} s")
        raw = bool(self.cap.set(cv2.CAP_PROP_FORMAT, -1))
        self.raw = raw
        size = (int(self.cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(self.cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
        asked = _asked(self.request)
        if self.nominal_fps is not None:
            asked["nominal_fps"] = self.nominal_fps
        return CameraSettings(size, None, "MJPG" if raw else "BGR3", None, "host", "opencv-ffmpeg", asked)

    def read(self, timeout_s: float) -> RawFrame:
        ok, data = self.cap.read()
        if not ok or data is None:
            raise SourceStopped("stopped sending frames (the stream ended or was silent "
                                f"for {self.request.timeout_s:g} s)")
        return RawFrame(_payload(data, self.raw))

    def close(self) -> None:
        if self.cap is not None:
            self.cap.release()


class V4l2Source:
    """``/dev/videoN``: OpenCV's V4L2 backend. Settings are set in the order the backend needs
    (fourcc, size, fps, exposure: each format change restarts the stream) and read back.

    Exposure: ``CAP_PROP_AUTO_EXPOSURE = 1`` (V4L2 manual mode; the 0.25/0.75 folklore applies
    only with OPENCV_VIDEOIO_V4L_RANGE_NORMALIZED) and ``CAP_PROP_EXPOSURE`` in the driver's
    ``exposure_absolute`` unit of 100 us. Timestamps: ``CAP_PROP_POS_MSEC`` is the kernel's buffer
    timestamp (CLOCK_MONOTONIC for most UVC drivers); it is trusted when it lies within a second of
    ``time.monotonic()``, else frames carry arrival times. Not testable in CI (docs/how-to/film-a-rig.md)."""

    live = True

    def __init__(self, request: CameraRequest) -> None:
        self.request = request
        self.cap: Any = None
        self.clock: Any = None

    def open(self, clock: Any) -> CameraSettings:  # pragma: no cover - needs a camera
        import cv2

        r, self.clock = self.request, clock
        self.cap = cv2.VideoCapture(r.target, cv2.CAP_V4L2)
        if not self.cap.isOpened():
            raise SourceStopped(f"could not open {r.target} (no such camera, or in use by another program)")
        if r.fourcc:
            code = sum(ord(ch) << (8 * i) for i, ch in enumerate(r.fourcc))  # VideoWriter_fourcc
            self.cap.set(cv2.CAP_PROP_FOURCC, code)
        if r.size:
            self.cap.set(cv2.CAP_PROP_FRAME_WIDTH, r.size[0])
            self.cap.set(cv2.CAP_PROP_FRAME_HEIGHT, r.size[1])
        if r.fps:
            self.cap.set(cv2.CAP_PROP_FPS, r.fps)
        if r.exposure_s:
            self.cap.set(cv2.CAP_PROP_AUTO_EXPOSURE, 1)
            self.cap.set(cv2.CAP_PROP_EXPOSURE, r.exposure_s * 1e4)
        fourcc = fourcc_text(self.cap.get(cv2.CAP_PROP_FOURCC))
        self.raw = fourcc == "MJPG" and bool(self.cap.set(cv2.CAP_PROP_CONVERT_RGB, 0))
        manual = self.cap.get(cv2.CAP_PROP_AUTO_EXPOSURE) == 1
        exposure = self.cap.get(cv2.CAP_PROP_EXPOSURE) / 1e4 if manual else None
        size = (int(self.cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(self.cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
        return CameraSettings(size, float(self.cap.get(cv2.CAP_PROP_FPS)) or None, fourcc, exposure,
                              "device", "opencv-v4l2", _asked(r))

    def read(self, timeout_s: float) -> RawFrame:  # pragma: no cover - needs a camera
        import cv2

        if not self.cap.grab():
            raise SourceStopped("stopped delivering frames (VIDIOC_DQBUF failed or timed out)")
        ok, data = self.cap.retrieve()
        if not ok:
            raise SourceStopped("delivered a buffer OpenCV could not retrieve")
        stamp = self.cap.get(cv2.CAP_PROP_POS_MSEC) / 1e3
        age = time.monotonic() - stamp
        t_device = self.clock.now() - age if stamp > 0 and 0 <= age < 1.0 else None
        return RawFrame(_payload(data, self.raw), t_device)

    def close(self) -> None:
        if self.cap is not None:
            self.cap.release()


def _asked(r: CameraRequest) -> dict[str, Any]:
    asked = {"size": f"{r.size[0]}x{r.size[1]}" if r.size else None, "fps": r.fps, "fourcc": r.fourcc,
             "exposure_s": r.exposure_s}
    return {k: v for k, v in asked.items() if v is not None}
