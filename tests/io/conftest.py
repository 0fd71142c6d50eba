"""Tiny emulators with known behaviour, registered for the transport tests only.

* ``sim://test_echo``: answers each LF-terminated line with ``ECHO <line>\\r\\n`` after
  ``latency`` seconds (option, default 0.05); prints ``READY\\r\\n`` at power-on.
* ``sim://test_ticker``: streams ``T <n>\\r\\n`` every ``period`` seconds (option, default 0.1),
  n counting from 1, and tells the port when its next line is due.
* ``sim://test_7e1``: like test_echo but expects 2400 baud 7E1 (A&D's default).
"""

from __future__ import annotations

from labkit.emulators.base import Emulator, register_emulator


@register_emulator
class EchoTestEmulator(Emulator):
    protocol = "test_echo"
    kind = "balance"

    def power_on(self, t: float) -> None:
        super().power_on(t)
        self._line = b""
        self.reply(b"READY\r\n", t)

    def handle(self, data: bytes, t: float) -> None:
        self._line += data
        while b"\n" in self._line:
            line, _, self._line = self._line.partition(b"\n")
            latency = float(self.options.get("latency", "0.05"))
            self.reply(b"ECHO " + line.rstrip(b"\r") + b"\r\n", t, latency=latency)


@register_emulator
class SevenE1TestEmulator(EchoTestEmulator):
    protocol = "test_7e1"
    serial_settings = {"baudrate": 2400, "bytesize": 7, "parity": "E"}


@register_emulator
class TickerTestEmulator(Emulator):
    protocol = "test_ticker"
    kind = "tachometer"

    def power_on(self, t: float) -> None:
        super().power_on(t)
        self._count = 0
        self._start = t

    @property
    def period(self) -> float:
        return float(self.options.get("period", "0.1"))

    def _due(self, n: int) -> float:
        return self._start + n * self.period

    def produce(self, t: float) -> None:
        while self._due(self._count + 1) <= t + 1e-12:
            self._count += 1
            self._queue(f"T {self._count}\r\n".encode(), self._due(self._count))

    def next_output_time(self, t: float) -> float | None:
        queued = self.next_ready_time()
        upcoming = self._due(self._count + 1)
        return upcoming if queued is None else min(queued, upcoming)
