"""What every motor driver shares: guarded writes, clocked reads, the >= 20 Hz keep-alive.

Safety rules (ARCHITECTURE rule 3, PROTOCOLS 5.3 rule 5): a driver never moves the motor on
open; once ``enable()`` is called a clock job (``clock.every(0.05, ...)``, a thread on a
real clock) re-sends the setpoint at 20 Hz so the controller's own command timeout never
fires while we are alive and always fires when we are not; ``stop()`` cancels the job and
commands zero without ever raising; ``close()`` and any exception leaving a ``with`` block
call ``stop()``.
"""

from __future__ import annotations

import threading
from typing import Any

import serial

from labkit.devices.base import MotorController
from labkit.errors import DeviceDisconnected, DeviceError, DeviceTimeout, SafetyError
from labkit.io.clock import Clock, PeriodicJob

KEEPALIVE_PERIOD_S = 0.05  # 20 Hz


def as_bool(value: Any) -> bool:
    """Rig-file/URL option to bool ('1', 'true', 'yes', 'on' or a true Python value)."""
    if isinstance(value, str):
        return value.strip().lower() in ("1", "true", "yes", "on")
    return bool(value)


class KeepAliveMotor(MotorController):
    """Base of the motor drivers: subclasses implement ``send_setpoint`` and ``send_zero``."""

    keepalive_period_s: float = KEEPALIVE_PERIOD_S

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        self.io_lock = threading.RLock()      # one query (request + reply) at a time
        self._write_lock = threading.Lock()   # one packet on the wire at a time
        self.enabled = False
        self.keepalive_count = 0
        self._job: PeriodicJob | None = None
        self._keepalive_error: BaseException | None = None
        self._closed = False

    # ---- byte I/O -----------------------------------------------------------------------
    def write(self, data: bytes, command: str) -> None:
        """Write one whole packet; a dead port becomes DeviceDisconnected naming the command.

        Only the write itself is locked, not a query's wait for its reply (``io_lock``), so
        the keep-alive thread is never held up by a slow status read.
        """
        with self._write_lock:
            try:
                self.port.write(data)
            except (serial.SerialException, OSError) as exc:
                raise DeviceDisconnected(self.name, command, self.last_bytes, str(exc)) from exc

    def read_available(self, command: str) -> bytes:
        try:
            waiting = self.port.in_waiting
            data = self.port.read(waiting) if waiting else b""
        except (serial.SerialException, OSError) as exc:
            raise DeviceDisconnected(self.name, command, self.last_bytes, str(exc)) from exc
        if data:
            self.last_bytes = (self.last_bytes + data)[-64:]
        return data

    def flush_input(self, command: str) -> None:
        try:
            self.port.reset_input_buffer()
        except (serial.SerialException, OSError) as exc:
            raise DeviceDisconnected(self.name, command, self.last_bytes, str(exc)) from exc

    def read_exact(self, n: int, timeout: float, command: str, quiet_s: float = 0.0) -> bytes:
        """Read exactly ``n`` bytes within ``timeout`` (clock time), polling the port.

        With ``quiet_s`` > 0 the line must then stay silent that long: extra bytes mean the
        reply was garbled (junk before/after it) and raise DeviceError.
        """
        deadline = self.clock.now() + timeout
        got = bytearray()
        while len(got) < n:
            got += self.read_available(command)
            if len(got) >= n:
                break
            if self.clock.now() >= deadline:
                raise DeviceTimeout(self.name, command, bytes(got) or self.last_bytes,
                                    f"{len(got)} of {n} reply bytes in {timeout} s")
            self.clock.sleep(0.001)
        if quiet_s > 0:
            self.clock.sleep(quiet_s)
            got += self.read_available(command)
        if len(got) != n:
            raise DeviceError(self.name, command, bytes(got),
                              f"garbled reply: {len(got)} bytes where {n} were expected")
        return bytes(got)

    # ---- keep-alive ---------------------------------------------------------------------
    def send_setpoint(self) -> None:  # pragma: no cover - interface
        """Write the current setpoint (or the protocol's keep-alive)."""
        raise NotImplementedError

    def send_zero(self) -> None:  # pragma: no cover - interface
        """Write the protocol's zero/brake/stop command."""
        raise NotImplementedError

    def _tick(self, _t: float) -> None:
        if not self.enabled:
            return
        try:
            self.send_setpoint()
            self.keepalive_count += 1
        except Exception as exc:  # noqa: BLE001 - reported to the caller by check_keepalive()
            self._keepalive_error = exc
            if self._job is not None:
                self._job.cancel()

    def start_keepalive(self) -> None:
        if self._job is None:
            self._job = self.clock.every(self.keepalive_period_s, self._tick, name=f"{self.name}-keepalive")

    def check_keepalive(self) -> None:
        """Raise (in the caller's thread) the error that stopped the keep-alive, after stopping."""
        if self._keepalive_error is not None:
            err = self._keepalive_error
            self._keepalive_error = None
            self.stop()
            raise err

    def require_enabled(self, command: str) -> None:
        self.check_keepalive()
        if self._closed:
            raise SafetyError(f"{self.name}: {command} after close")
        if not self.enabled:
            raise SafetyError(f"{self.name}: {command} refused: the motor is not enabled (call enable())")

    def stop(self) -> None:
        """Cancel the keep-alive and command zero. Never raises (a dead port is ignored)."""
        self.enabled = False
        if self._job is not None:
            self._job.cancel()
            self._job = None
        try:
            self.send_zero()
        except Exception:  # noqa: BLE001 - stop() must not raise; the port may be dead
            pass

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        super().close()
