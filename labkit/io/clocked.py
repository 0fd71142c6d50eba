"""A ``serial.SerialBase`` whose waits go through a :class:`~labkit.io.clock.Clock`.

Base of labkit's own port classes (``sim://``, ``replay://``, ``record://``). pyserial's
``read_until`` measures its timeout on the wall clock; here it is measured on the port's
clock, so a virtual clock replays timeouts instantly and deterministically.
"""

from __future__ import annotations

import random

import serial
from serial.serialutil import SerialBase

from labkit.io.clock import Clock, current_clock

#: the settings a wire carries (a port opened with others talks to the device wrongly)
LINE_SETTINGS = ("baudrate", "bytesize", "parity", "stopbits")
#: virtual-clock step while a read waits for something the clock cannot foresee
VIRTUAL_POLL_S = 0.005
#: real-clock polling interval while a read waits
REAL_POLL_S = 0.001


def poll_step(period: float, now: float, deadline: float | None) -> float:
    """How long a waiting read sleeps: ``period``, cut short at the read's ``deadline``."""
    return period if deadline is None else max(0.0, min(period, deadline - now))


class ClockedSerial(SerialBase):
    """Common plumbing: the clock, no-op modem lines, a clock-based ``read_until``."""

    _timeout: float | None  # SerialBase's read timeout (s), set by its ``timeout`` property

    def __init__(self, *args, **kwargs) -> None:
        self.clock: Clock | None = None
        super().__init__(*args, **kwargs)

    def _resolve_clock(self) -> Clock:
        if self.clock is None:
            self.clock = current_clock()
        return self.clock

    def _require_open(self) -> None:
        if not self.is_open:
            raise serial.PortNotOpenError()

    def _require_openable(self) -> None:
        """pyserial's checks at the start of ``open()``."""
        if self.is_open:
            raise serial.SerialException("Port is already open.")
        if self._port is None:
            raise serial.SerialException("Port must be configured before it can be used.")

    # -- modem lines and buffers that have no meaning without a wire ------------------
    def _reconfigure_port(self) -> None:
        pass

    def _update_rts_state(self) -> None:
        pass

    def _update_dtr_state(self) -> None:
        pass

    def _update_break_state(self) -> None:
        pass

    def reset_output_buffer(self) -> None:
        self._require_open()

    @property
    def out_waiting(self) -> int:
        self._require_open()
        return 0

    # modem status lines of a wire that is always ready: clear to send, data set ready,
    # carrier detected, no ring
    cts = dsr = cd = property(lambda self: True)
    ri = property(lambda self: False)

    def flush(self) -> None:
        pass

    # -- reading ------------------------------------------------------------------------
    def read_until(self, expected: bytes = b"\n", size: int | None = None) -> bytes:
        """Read until ``expected``, ``size`` bytes or the port timeout (measured on the clock)."""
        clock = self._resolve_clock()
        deadline = None if self._timeout is None else clock.now() + self._timeout
        line = bytearray()
        while True:
            saved = self._timeout
            if deadline is not None:
                self._timeout = max(0.0, deadline - clock.now())
            try:
                chunk = self.read(1)
            finally:
                self._timeout = saved
            if not chunk:
                break
            line += chunk
            if line.endswith(expected) or (size is not None and len(line) >= size):
                break
            if deadline is not None and clock.now() >= deadline:
                break
        return bytes(line)

    def settings_summary(self) -> dict[str, object]:
        """The line settings as JSON-friendly values (for cassettes and mismatch checks)."""
        return {
            "baudrate": self._baudrate,
            "bytesize": self._bytesize,
            "parity": self._parity,
            "stopbits": self._stopbits,
            "timeout": self._timeout,
        }


def garble(data: bytes, rng: random.Random) -> bytes:
    """Bytes as a UART at the wrong baud/format sees them: same length, unrelated values."""
    return bytes(rng.randrange(256) for _ in data)
