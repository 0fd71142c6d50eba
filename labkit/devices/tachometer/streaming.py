"""The part every streaming tachometer shares: a reader job filling a timestamped buffer.

A tachometer talks without being asked. One :class:`~labkit.devices.stream_reader.StreamReader`
per device (a thread on a real clock, a clock job on a virtual one) cuts the bytes into
frames and hands each to :meth:`StreamingTachometer.parse_frame`; accepted readings go into
a :class:`~labkit.devices.link.ReadingBuffer` that ``latest()``, ``readings_since(t)`` and
``wait_reading(timeout)`` read without ever touching the port. A reader failure (the USB
adapter unplugged mid-read) surfaces in the caller's thread as
:class:`~labkit.errors.DeviceDisconnected`.
"""

from __future__ import annotations

from typing import Any

import serial

from labkit.devices.base import Tachometer
from labkit.devices.link import ReadingBuffer
from labkit.devices.stream_reader import StreamReader
from labkit.io.clock import Clock
from labkit.readings import Reading


class StreamingTachometer(Tachometer):
    """Base of the stream-reading tachometer drivers (subclasses give framer and parser)."""

    #: readings kept in memory (about 1 h at 10 Hz)
    history: int = 50_000
    #: how often the reader pumps the port (s)
    reader_period: float = 0.005

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        self.reading_buffer = ReadingBuffer(self.history, before_read=self._check_reader)
        self.frames_rejected = 0
        self.reader = StreamReader(port, clock, self.make_framer(), self._on_frame,
                                   device=self.name, period=self.reader_period)
        try:
            port.reset_input_buffer()
        except (serial.SerialException, OSError, AttributeError):
            pass  # the reader will report a dead port on its first read
        self.reader.start()

    # ---- subclass hooks -----------------------------------------------------------------
    def make_framer(self) -> Any:
        raise NotImplementedError

    def parse_frame(self, t: float, frame: bytes) -> Reading | None:
        """Turn one frame into a reading, or None (comment, reply, garbage)."""
        raise NotImplementedError

    # ---- buffer -------------------------------------------------------------------------
    def _on_frame(self, t: float, frame: bytes) -> None:
        try:
            reading = self.parse_frame(t, frame)
        except ValueError:
            self.frames_rejected += 1
            return
        if reading is not None:
            self.reading_buffer.add(reading)

    def _check_reader(self) -> None:
        self.last_bytes = self.reader.last_bytes
        self.reader.check()

    def latest(self) -> Reading | None:
        return self.reading_buffer.latest()

    def readings_since(self, t: float) -> list[Reading]:
        return self.reading_buffer.since(t)

    def close(self) -> None:
        self.reader.stop()
        super().close()
