"""Continuous balance output (MT-SICS ``SIR``, A&D stream/``SIR``, HX711 sketches) read by
one :class:`~labkit.devices.stream_reader.StreamReader` per balance into a timestamped buffer.

On a real clock the reader is a thread, so a slow motor write never blocks the balance
(docs/explanation/architecture.md#streaming-devices); on a virtual clock the clock pumps it while time
advances, so replay is
deterministic. While the stream runs, ``read()`` returns the next new reading from the
buffer; commands that need the port (zero, tare, identify) pause the stream around them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

import serial

from labkit.devices.link import FrameError, LineFramer, LineLink, ReadingBuffer
from labkit.devices.stream_reader import StreamReader
from labkit.errors import DeviceError, DeviceTimeout
from labkit.io.clock import Clock
from labkit.readings import Reading


class ContinuousReadings:
    """A reader pumping ``port`` and a ring buffer of the readings ``to_reading`` makes."""

    def __init__(self, port: serial.SerialBase, clock: Clock, device: str,
                 to_reading: Callable[[float, bytes], Reading | None],
                 read_eol: bytes = b"\n", history: int = 4096, period: float = 0.005) -> None:
        self.clock = clock
        self.device = device
        self.to_reading = to_reading
        self.bad_frames = 0
        self.device_errors: list[DeviceError] = []
        self.reader = StreamReader(port, clock, LineFramer(read_eol), self._on_frame,
                                   device=device, period=period)
        self.buffer = ReadingBuffer(history, before_read=self.reader.check)

    def _on_frame(self, t: float, frame: bytes) -> None:
        if not frame:
            return
        try:
            reading = self.to_reading(t, frame)
        except FrameError:
            self.bad_frames += 1
            return
        except DeviceError as exc:  # an error line in the stream: kept, the stream goes on
            self.device_errors.append(exc)
            return
        if reading is not None:
            self.buffer.add(reading)

    def start(self) -> None:
        self.reader.start()

    def stop(self) -> None:
        self.reader.stop()

    def check(self) -> None:
        """Raise what the reader hit (an unplugged port) in the caller's thread."""
        self.reader.check()

    def latest(self) -> Reading | None:
        return self.buffer.latest()

    def readings_since(self, t: float) -> list[Reading]:
        return self.buffer.since(t)

    def wait_new(self, since: float, timeout: float, poll_s: float = 0.005) -> Reading:
        """The first reading received after ``since``; DeviceTimeout after ``timeout`` s."""
        deadline = self.clock.now() + timeout
        while True:
            new = self.readings_since(since)
            if new:
                return new[0]
            if self.clock.now() >= deadline:
                raise DeviceTimeout(self.device, "stream", self.reader.last_bytes,
                                    f"no reading in {timeout:g} s of continuous output")
            self.clock.sleep(poll_s)


class ContinuousMixin:
    """Adds ``start_continuous``/``stop_continuous``/``latest``/``readings_since`` to a
    balance driver. The driver provides ``_begin_stream`` (e.g. send ``SIR``),
    ``_end_stream`` (e.g. ``@`` or ``C``) and ``_stream_reading(t, line)``."""

    stream: ContinuousReadings | None = None
    link: LineLink
    read_eol: bytes = b"\n"

    def _begin_stream(self) -> None:  # pragma: no cover - per protocol
        raise NotImplementedError

    def _end_stream(self) -> None:  # pragma: no cover - per protocol
        raise NotImplementedError

    def _stream_reading(self, t: float, line: bytes) -> Reading | None:  # pragma: no cover
        raise NotImplementedError

    def start_continuous(self) -> None:
        """Ask for continuous output and start the reader (idempotent)."""
        if self.stream is not None:
            return
        self._begin_stream()
        self.stream = ContinuousReadings(self.port, self.clock, self.name,  # type: ignore[attr-defined]
                                         self._stream_reading, self.read_eol)
        self.stream.start()

    def stop_continuous(self) -> None:
        """Stop the reader and the device's continuous output."""
        if self.stream is None:
            return
        self.stream.stop()
        self.stream = None
        self._end_stream()

    @property
    def continuous(self) -> bool:
        return self.stream is not None

    def latest(self) -> Reading | None:
        """The newest reading of the continuous stream (None before the first one)."""
        return self.stream.latest() if self.stream is not None else None

    def readings_since(self, t: float) -> list[Reading]:
        """All streamed readings received at clock time > t, oldest first."""
        return self.stream.readings_since(t) if self.stream is not None else []

    @contextmanager
    def paused(self) -> Iterator[None]:
        """Give the port back to request/response commands for a moment."""
        was = self.stream is not None
        if was:
            self.stop_continuous()
        try:
            yield
        finally:
            if was:
                self.start_continuous()

    def close(self) -> None:
        if self.stream is not None:
            self.stream.stop()
            self.stream = None
        super().close()  # type: ignore[misc]
