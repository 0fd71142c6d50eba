"""What every motor driver shares: guarded writes, clocked reads, the >= 20 Hz keep-alive.

Safety rules (docs/explanation/architecture.md#safe-state-on-every-exit-path,
docs/explanation/device-rules.md#driver-rules rule 5): a driver never moves the motor on
open; once ``enable()`` is called a clock job (``clock.every(0.05, ...)``, a thread on a
real clock) re-sends the setpoint at 20 Hz so the controller's own command timeout never
fires while we are alive and always fires when we are not; ``stop()`` cancels the job and
commands zero without ever raising; ``close()`` and any exception leaving a ``with`` block
call ``stop()``.

The controller's own watchdog (its command timeout) is what stops the motor when nothing
in labkit is left to do it (SIGKILL, the OOM killer, a crash: docs/explanation/safety.md). A driver
names the option that declares it (``watchdog_option``) and says how to switch it on
(``watchdog_advice``); :func:`watchdog_problem` refuses a real-hardware rig without it.
A duty or speed that is not a finite number never reaches the wire: the motor is commanded
to zero and :class:`SafetyError` raised (:meth:`KeepAliveMotor.finite`). ``stop()`` never
raises but remembers why a STOP could not be delivered (``stop_error``).
"""

from __future__ import annotations

import math
import threading
from typing import Any, ClassVar

import serial

from labkit.devices.base import MotorController
from labkit.devices.link import PORT_ERRORS, LinkTailMixin, PacketLink
from labkit.errors import DeviceDisconnected, SafetyError
from labkit.io.clock import Clock, PeriodicJob

KEEPALIVE_PERIOD_S = 0.05  # 20 Hz
#: the controller's command timeout must be at least this many keep-alive periods ...
WATCHDOG_MIN_PERIODS = 4
#: ... and at most this long, so a dead labkit releases the motor within a second
WATCHDOG_MAX_MS = 1000.0


def as_bool(value: Any) -> bool:
    """Rig-file/URL option to bool ('1', 'true', 'yes', 'on' or a true Python value)."""
    if isinstance(value, str):
        return value.strip().lower() in ("1", "true", "yes", "on")
    return bool(value)


def stop_failure_text(exc: BaseException) -> str:
    """Why a STOP did not reach the controller, in words a person acts on."""
    cause = exc.__cause__ if exc.__cause__ is not None else exc
    if isinstance(exc, DeviceDisconnected) or isinstance(cause, PORT_ERRORS):
        return f"port gone ({cause})"
    return f"{type(exc).__name__}: {exc}"


class KeepAliveMotor(LinkTailMixin, MotorController):
    """Base of the motor drivers: subclasses implement ``send_setpoint`` and ``send_zero``."""

    keepalive_period_s: float = KEEPALIVE_PERIOD_S
    #: driver option declaring the controller's command timeout in ms (None: built in)
    watchdog_option: ClassVar[str | None] = None
    #: the controller's built-in command timeout in ms, if it has one that cannot be turned off
    builtin_watchdog_ms: ClassVar[float | None] = None
    #: how to switch the controller's command timeout on (shown by rig checks and probe)
    watchdog_advice: ClassVar[str] = ""

    @classmethod
    def watchdog_problem(cls, options: dict[str, Any], required: bool = True) -> tuple[str, str] | None:
        """``(key, reason)`` when ``options`` do not declare a usable command timeout, else None.

        ``required``: real hardware (emulated ``sim://`` controllers may leave it out).
        """
        if cls.builtin_watchdog_ms is not None or cls.watchdog_option is None:
            return None
        key = f"options.{cls.watchdog_option}"
        value = options.get(cls.watchdog_option)
        low = cls.keepalive_period_s * 1000 * WATCHDOG_MIN_PERIODS
        if value is None and not required:
            return None
        if value is None:
            return key, (f"required for real hardware: the {cls.protocol} controller's own command "
                         f"timeout stops the motor when labkit dies (SIGKILL, crash, power cut of the "
                         f"PC); {cls.watchdog_advice}, then declare it here, e.g. "
                         f"options = {{ {cls.watchdog_option} = 500 }} (docs/explanation/safety.md)")
        try:
            ms = float(value)
        except (TypeError, ValueError):
            return key, f"{value!r} is not a number of milliseconds"
        if not math.isfinite(ms) or not low <= ms <= WATCHDOG_MAX_MS:
            period_ms = cls.keepalive_period_s * 1000
            return key, (f"{value!r} ms: must be {low:.0f}..{WATCHDOG_MAX_MS:.0f} ms (at least "
                         f"{WATCHDOG_MIN_PERIODS} keep-alive periods of {period_ms:.0f} ms, "
                         f"at most {WATCHDOG_MAX_MS / 1000:.0f} s); {cls.watchdog_advice}")
        return None

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        super().__init__(port, clock, name, **options)
        self.io_lock = threading.RLock()      # one query (request + reply) at a time
        self.link = PacketLink(port, clock, self.name)  # one packet on the wire at a time
        self.enabled = False
        self.keepalive_count = 0
        self._job: PeriodicJob | None = None
        self._keepalive_error: BaseException | None = None
        self._closed = False
        #: why the last STOP could not be delivered (None: delivered)
        self.stop_error: str | None = None

    def finite(self, value: float, command: str) -> float:
        """``value`` if it is a finite number; else command zero and raise SafetyError.

        NaN/inf gains or speeds upstream must never become full duty at the wire
        (``min(1.0, nan)`` is 1.0).
        """
        try:
            number = float(value)
        except (TypeError, ValueError):
            number = math.nan
        if math.isfinite(number):
            return number
        self.stop()
        raise SafetyError(f"{self.name}: {command} {value!r} is not a finite number; refused, "
                          "motor commanded to zero")

    # ---- byte I/O (the transport: labkit.devices.link.PacketLink) ------------------------
    def write(self, data: bytes, command: str) -> None:
        """Write one whole packet (see :meth:`PacketLink.write <labkit.devices.link.PacketLink.write>`)."""
        self.link.write(data, command)

    def read_available(self, command: str) -> bytes:
        return self.link.read_available(command)

    def flush_input(self, command: str) -> None:
        self.link.flush_input(command)

    def read_exact(self, n: int, timeout: float, command: str, quiet_s: float = 0.0) -> bytes:
        """Exactly ``n`` bytes within ``timeout`` (see :meth:`labkit.devices.link.PacketLink.read_exact`)."""
        return self.link.read_exact(n, timeout, command, quiet_s)

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
        """Cancel the keep-alive and command zero. Never raises: when the STOP cannot be
        delivered (a dead port) the reason is kept in ``stop_error`` for the caller to report."""
        self.enabled = False
        if self._job is not None:
            self._job.cancel()
            self._job = None
        try:
            self.send_zero()
        except Exception as exc:  # noqa: BLE001 - stop() must not raise; the port may be dead
            self.stop_error = stop_failure_text(exc)
        else:
            self.stop_error = None

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        super().close()
