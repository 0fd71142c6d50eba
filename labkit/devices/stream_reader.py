"""Reading unsolicited device output into a timestamped buffer without blocking anyone.

A :class:`StreamReader` owns one port's input. ``pump()`` reads whatever bytes are there
(never waiting), cuts them into frames with a framer (a :class:`~labkit.devices.link.Framer`)
and hands each frame with its receive time to a callback. On a real clock a periodic job (its
own thread) pumps continuously, so a slow motor write never blocks a fast sensor
(docs/explanation/architecture.md#streaming-devices); on a virtual clock the clock runs the
same job while time advances, so replay is deterministic.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable

import serial

from labkit.devices.link import Framer
from labkit.errors import DeviceDisconnected
from labkit.io.calls import read_time
from labkit.io.clock import Clock, PeriodicJob


class StreamReader:
    """Pump a port into ``on_frame(t, frame)``; runs on the clock every ``period`` seconds."""

    def __init__(
        self,
        port: serial.SerialBase,
        clock: Clock,
        framer: Framer,
        on_frame: Callable[[float, bytes], None],
        device: str = "",
        period: float = 0.005,
        history: int = 4096,
    ) -> None:
        self.port = port
        self.clock = clock
        self.framer = framer
        self.on_frame = on_frame
        self.device = device
        self.period = period
        self.tail: deque[int] = deque(maxlen=history)  # recent raw bytes, for error messages
        self.error: BaseException | None = None
        self._lock = threading.Lock()
        self._job: PeriodicJob | None = None

    @property
    def last_bytes(self) -> bytes:
        return bytes(self.tail)[-64:]

    def start(self) -> None:
        if self._job is None:
            self._job = self.clock.every(self.period, self._tick, name=f"{self.device}-reader")

    def stop(self) -> None:
        if self._job is not None:
            self._job.cancel()
            self._job = None

    def _tick(self, _t: float) -> None:
        if self.error is not None:
            return
        try:
            self.pump()
        except Exception as exc:  # noqa: BLE001 - kept and re-raised to the caller via check()
            self.error = exc

    def check(self) -> None:
        """Raise the reader's error in the caller's thread; a port error (pyserial's, or EIO from
        a hung-up pty/USB adapter) as :class:`~labkit.errors.DeviceDisconnected`."""
        if self.error is not None:
            err = self.error
            if isinstance(err, (serial.SerialException, OSError)):
                raise DeviceDisconnected(self.device, "stream", self.last_bytes,
                                         f"port disconnected ({err})") from err
            raise err

    def pump(self) -> int:
        """Read what is waiting now, frame it, deliver frames. Returns the number of frames."""
        with self._lock:
            waiting = self.port.in_waiting
            if not waiting:
                return 0
            data = self.port.read(waiting)
            if not data:
                return 0
            t = read_time(self.port, self.clock)
            self.tail.extend(data)
            frames = self.framer.feed(data)
        for frame in frames:
            self.on_frame(t, frame)
        return len(frames)
