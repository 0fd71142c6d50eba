"""What the drivers share between the port and their readings (issue 12, first step).

* :class:`ReadingBuffer` - the one buffer of a streaming device's readings (tachometers,
  balances in continuous mode): bounded, time-ordered, thread-safe; ``latest()`` and
  ``since(t)`` never touch the port.
* :class:`~labkit.devices.loadcell.linkio.LineLink` (request/response over lines with
  timeouts, resync and the drivers' error messages) is re-exported here; it moves here, with a
  binary-packet link for the motor controllers, in the next step (docs/DEVELOPING.md).
"""

from __future__ import annotations

import bisect
import threading
from collections.abc import Callable

from labkit.devices.base import Reading
from labkit.devices.loadcell.linkio import FrameError, LineLink

__all__ = ["FrameError", "LineLink", "ReadingBuffer"]


class ReadingBuffer:
    """The newest ``history`` readings of one device, oldest first.

    Readings are added by one reader (a thread on a real clock, a clock job on a virtual one)
    in clock order; any thread may read. When full, the oldest tenth is dropped at once (so
    adding stays cheap): the buffer then holds between 0.9 and 1.0 times ``history``.
    """

    def __init__(self, history: int, before_read: Callable[[], None] | None = None) -> None:
        if history < 1:
            raise ValueError(f"history {history}: must be >= 1")
        self.history = history
        #: called before every read (the device's reader raises what it hit, e.g. an unplug)
        self.before_read = before_read
        self._times: list[float] = []
        self._readings: list[Reading] = []
        self._lock = threading.Lock()

    def add(self, reading: Reading) -> None:
        with self._lock:
            self._times.append(reading.t)
            self._readings.append(reading)
            if len(self._readings) > self.history:
                drop = len(self._readings) - self.history + self.history // 10
                del self._times[:drop]
                del self._readings[:drop]

    def latest(self) -> Reading | None:
        """The newest reading, or None before the first."""
        if self.before_read is not None:
            self.before_read()
        with self._lock:
            return self._readings[-1] if self._readings else None

    def since(self, t: float) -> list[Reading]:
        """The readings received at clock time > ``t``, oldest first."""
        if self.before_read is not None:
            self.before_read()
        with self._lock:
            return self._readings[bisect.bisect_right(self._times, t):]

    def __len__(self) -> int:
        with self._lock:
            return len(self._readings)
