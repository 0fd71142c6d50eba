"""The camera device: a frame source behind a grab thread, opened from a URL like every device.

:func:`open_camera` turns a rig-file port URL into a :class:`Camera` (``record://`` wraps a
source and stores every frame handed to the run; ``replay://`` serves a frame cassette, with
``?mode=faithful`` at its recorded times, burst by burst: :mod:`labkit.devices.camera.faithful`).

Live sources (a webcam, an MJPEG stream) are drained all the time by a grab thread: OpenCV's
queued buffers would otherwise hand a slow reader frames several periods old. Frames that arrive
while no burst is collecting are counted (``discarded``) and dropped; the newest is kept for
:meth:`Camera.latest`. Emulated and replayed sources are pulled on the run's clock instead (a
virtual clock must not be slept on by two threads).

Every wait has a timeout (``timeout_s`` in the URL, default 2 s): a camera that sends nothing
for that long ends the burst with a one-line :class:`~labkit.errors.DeviceTimeout` naming the
camera, its URL and what it stopped doing; it never hangs a run. When recording, a failed
burst's frames and its fault are written to the frame cassette, so a replay fails the same burst
the same way.
"""

from __future__ import annotations

import threading
import time
from dataclasses import replace
from typing import Any, ClassVar

from labkit.devices.base import Device
from labkit.devices.camera.cassette import FrameCassetteWriter, RecordedFault, ReplaySource
from labkit.devices.camera.faithful import FaithfulFrameSource
from labkit.devices.camera.frames import CameraSettings, Frame
from labkit.devices.camera.sources import HttpMjpegSource, SourceStopped, V4l2Source
from labkit.devices.camera.urls import DEFAULT_TIMEOUT_S, parse_camera_url
from labkit.devices.registry import register_driver
from labkit.errors import DeviceError, DeviceTimeout, PortURLError
from labkit.io.clock import Clock
from labkit.io.urls import parse_record_url, parse_replay_url, split_scheme


@register_driver
class Camera(Device):
    """A camera (kind ``camera``, protocol ``frames``): :meth:`burst` returns the next N frames.

    ``settings`` are what the camera accepted (read back); ``received``, ``dropped`` (frames the
    camera lost: sequence gaps, or time gaps over 1.5 periods when it has no sequence numbers)
    and ``discarded`` (drained while no burst was collecting) are counts since opening."""

    kind = "camera"
    protocol = "frames"
    default_serial: ClassVar[dict[str, Any]] = {}
    option_names: ClassVar[frozenset[str] | None] = frozenset()  # settings live in the URL

    def __init__(self, source: Any, clock: Clock, name: str = "", url: str = "", timeout_s: float =
                 DEFAULT_TIMEOUT_S, recorder_path: str | None = None, **options: Any) -> None:
        super().__init__(source, clock, name=name or "camera", **options)
        self.source = source
        self.url = url
        self.timeout_s = timeout_s
        self.settings: CameraSettings = source.open(clock)
        #: the rate drops are counted against when frames have no sequence numbers: the accepted
        #: one, else what the URL declares for a stream (``nominal_fps``), else None (not counted)
        self.nominal_fps: float | None = self.settings.fps or getattr(source, "nominal_fps", None)
        self.recorder = FrameCassetteWriter(recorder_path, url, self.settings) if recorder_path else None
        self.received = self.dropped = self.discarded = 0
        self._seq = -1
        self._last: Frame | None = None
        self._last_arrival = time.monotonic()
        self._collect: list[Frame] | None = None
        self._error: str | None = None
        self._cond = threading.Condition()
        self._closing = False
        self._thread: threading.Thread | None = None
        if source.live:
            self._thread = threading.Thread(target=self._grab, name=f"labkit-grab-{self.name}", daemon=True)
            self._thread.start()

    # ---- frames in ---------------------------------------------------------------------------
    def _stamp(self, raw: Any) -> Frame:
        t_host = raw.t_host if raw.t_host is not None else self.clock.now()
        seq = raw.seq if raw.seq is not None else self._seq + 1
        dropped = raw.dropped_before
        if dropped is None:
            dropped = max(0, seq - self._seq - 1) if self._seq >= 0 else 0
            fps = self.nominal_fps
            if raw.seq is None and fps and self._last is not None:  # no sequence: gaps in time
                t_new = raw.t_device if raw.t_device is not None else t_host
                dropped = max(0, round((t_new - self._last.t) * fps) - 1) \
                    if (t_new - self._last.t) * fps > 1.5 else 0
        self._seq = seq
        return Frame(seq, t_host, raw.t_device, raw.payload, dropped, meta=raw.meta)

    def _accept(self, frame: Frame) -> None:
        self.received += 1
        self.dropped += frame.dropped_before
        self._last = frame
        if self._collect is not None:
            self._collect.append(frame)
        else:
            self.discarded += 1

    def _grab(self) -> None:
        while not self._closing:
            try:
                raw = self.source.read(self.timeout_s)
            except SourceStopped as exc:
                with self._cond:
                    self._error = str(exc)
                    self._cond.notify_all()
                return
            except Exception as exc:  # noqa: BLE001 - the waiter reports it, with the camera's name
                with self._cond:
                    self._error = f"failed: {type(exc).__name__}: {exc}"
                    self._cond.notify_all()
                return
            with self._cond:
                self._accept(self._stamp(raw))
                self._last_arrival = time.monotonic()
                self._cond.notify_all()

    # ---- frames out --------------------------------------------------------------------------
    def _fault(self, what: str, got: int, n: int) -> DeviceError:
        cls = DeviceTimeout if "silent" in what or "stopped" in what else DeviceError
        return cls(f"camera {self.name} at {self.url}", "burst", b"", f"{what} ({got} of {n} frames of the "
                   f"burst, {self.received} received since opening)")

    def burst(self, n: int, step: Any = None, timeout_s: float | None = None) -> list[Frame]:
        """The next ``n`` frames (recorded under ``step`` when recording). Raises DeviceTimeout if
        the camera sends nothing for ``timeout_s`` (default: the URL's ``timeout_s``)."""
        if n < 1:
            raise ValueError("a burst needs at least one frame")
        limit = self.timeout_s if timeout_s is None else timeout_s
        begin = getattr(self.source, "begin_burst", None)
        if begin is not None:  # a faithful replay matches the burst to the recording's
            begin(n, step)
        frames: list[Frame] = []
        try:
            if self.source.live:
                self._wait(n, limit, frames)
            else:
                self._pull(n, limit, frames)
        except DeviceError as exc:
            if self.recorder is not None:  # the frames it did send, then how the burst ended
                self.recorder.write(frames, step)
                self.recorder.write_fault(exc, step, n, self.clock.now())
            raise
        if self.recorder is not None:
            self.recorder.write(frames, step)
        return frames

    def _pull(self, n: int, limit: float, out: list[Frame]) -> None:
        self._collect = out
        try:
            while len(out) < n:
                try:
                    raw = self.source.read(limit)
                except SourceStopped as exc:
                    raise self._fault(str(exc), len(out), n) from None
                except RecordedFault as fault:  # a replayed burst the recorded camera failed
                    device = fault.device or f"camera {self.name} at {self.url}"
                    raise fault.kind(device, "burst", b"", fault.reason) from None
                frame = self._stamp(raw)
                if not out and frame.dropped_before:  # slots that passed while no burst was taken:
                    self.discarded += frame.dropped_before  # not read, as a grab thread discards them
                    frame = replace(frame, dropped_before=0)
                self._accept(frame)
        finally:
            self._collect = None

    def _wait(self, n: int, limit: float, out: list[Frame]) -> None:
        with self._cond:
            self._collect = out
            start = time.monotonic()
            try:
                while len(out) < n:
                    if self._error is not None:
                        raise self._fault(self._error, len(out), n)
                    silent = time.monotonic() - max(self._last_arrival, start)
                    if silent >= limit:
                        raise self._fault(f"stopped sending frames: silent for {silent:.1f} s "
                                          f"(timeout {limit:g} s)", len(out), n)
                    self._cond.wait(timeout=min(0.1, limit - silent))
            finally:
                self._collect = None

    def latest(self) -> Frame | None:
        """The newest frame received (live sources), or None."""
        return self._last

    def describe(self) -> dict[str, Any]:
        """Settings accepted plus the counts (the probe's JSON line)."""
        return {"camera": self.name, "url": self.url, **self.settings.as_json(), "received": self.received,
                "dropped": self.dropped, "discarded": self.discarded}

    def identify(self) -> dict[str, Any]:
        return self.settings.as_json()

    def close(self) -> None:
        """Stop the grab thread (it ends within one read: at most ``timeout_s``), then release the
        source; a source still blocked in a read is left to the process's exit rather than
        released under it (OpenCV must not free a capture another thread is reading)."""
        self._closing = True
        try:
            if self._thread is not None and self._thread is not threading.current_thread():
                self._thread.join(self.timeout_s + 1.0)
            if self._thread is None or not self._thread.is_alive():
                self.source.close()
        finally:
            if self.recorder is not None:
                self.recorder.close()
                self.recorder = None


#: frame sources by URL kind; ``sim`` is registered by :mod:`labkit.emulators` when imported
#: (the emulators own ``sim://``: docs/decisions/0005-emulators-own-sim-urls.md)
SOURCES: dict[str, Any] = {"http": HttpMjpegSource, "v4l2": V4l2Source}


def register_camera_source(kind: str, factory: Any) -> None:
    """Make ``factory(request)`` open camera URLs of ``kind`` (``sim``: the emulated camera)."""
    SOURCES[kind] = factory


def open_source(url: str) -> tuple[Any, float]:
    """The frame source a camera URL describes and its timeout (s)."""
    request = parse_camera_url(url)
    if request.kind not in SOURCES:
        raise PortURLError(url, "sim://camera is served by labkit.emulators; import it first")
    return SOURCES[request.kind](request), request.timeout_s


def open_camera(url: str, clock: Clock, name: str = "camera", **options: Any) -> Camera:
    """A :class:`Camera` on ``url`` (module docstring). Faults opening it are DeviceErrors naming
    the camera and URL; a malformed URL a PortURLError."""
    scheme, _ = split_scheme(url)
    recorder = None
    shown = url  # the URL messages and the cassette name: the camera's own, not record://
    timeout = DEFAULT_TIMEOUT_S
    if scheme == "replay":
        spec = parse_replay_url(url)
        source: Any = (FaithfulFrameSource(spec.cassette) if spec.mode == "faithful"
                       else ReplaySource(spec.cassette, spec.mode))
    else:
        inner = url
        if scheme == "record":
            rec = parse_record_url(url)
            inner, recorder = rec.inner_url, rec.cassette
            shown = inner
        try:
            source, timeout = open_source(inner)
        except SourceStopped as exc:
            raise PortURLError(inner, str(exc)) from None
    try:
        return Camera(source, clock, name=name, url=shown, timeout_s=timeout, recorder_path=recorder,
                      **options)
    except SourceStopped as exc:
        source.close()
        raise DeviceError(f"camera {name} at {shown}", "open", b"", str(exc)) from None
    except BaseException:
        source.close()
        raise
