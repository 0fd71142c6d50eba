"""What every driver shares: the device-class interfaces (what a driver reads is a
:class:`labkit.readings.Reading`; the registry of drivers by kind and protocol is
:mod:`labkit.devices.registry`).

A driver is one small class per real protocol. It receives an *open* serial port (any
``serial.SerialBase``: a real device, ``sim://``, ``replay://``, a pty) and a
:class:`~labkit.io.clock.Clock`; it never opens ports and never sleeps on the wall clock.
Parsing and formatting live in pure module-level functions (``parse_*`` / ``format_*``)
so they can be fuzzed without I/O.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar, Self

import serial

from labkit.io.clock import Clock
from labkit.readings import Reading

#: controller errors that mean the motor was driven past the controller's range (current,
#: temperature, speed): a status's ``overload``. Others (a Pololu SMC's safe-start at rest, a
#: command timeout, a low supply) are listed in ``errors`` but are no overload (issue 27: a
#: motor at rest reported ``"overload": true`` for its safe-start bit).
OVERLOAD_ERRORS = frozenset({
    "over_temperature", "motor_driver_error",                  # Pololu SMC (bits 7, 8)
    "abs_over_current", "over_temp_fet", "over_temp_motor", "drv", "overspeed", "abs_overspeed",  # VESC
})


@dataclass(frozen=True)
class MotorStatus:
    """Controller telemetry. ``duty`` in -1..1; ``speed_rad_s`` when the controller measures it."""

    t: float
    duty: float
    target_duty: float
    speed_rad_s: float | None = None
    input_voltage_v: float | None = None
    temperature_c: float | None = None
    errors: frozenset[str] = field(default_factory=frozenset)
    raw: bytes = b""

    def as_json(self) -> dict[str, Any]:
        return {
            "t": self.t,
            "value": self.duty,
            "unit": "1",
            "stable": not self.errors,
            "overload": bool(self.errors & OVERLOAD_ERRORS),
            "speed_rad_s": self.speed_rad_s,
            "input_voltage_v": self.input_voltage_v,
            "temperature_c": self.temperature_c,
            "errors": sorted(self.errors),
            "raw": self.raw.decode("latin-1"),
        }


def unknown_options(cls: type[Device], options: dict[str, Any]) -> list[str]:
    """The names in ``options`` that driver class ``cls`` does not read (a typo would
    otherwise be ignored silently, e.g. a pulses-per-revolution that never reaches it)."""
    if cls.option_names is None:
        return []
    return sorted(set(options) - cls.option_names)


def unknown_options_message(cls: type[Device], unknown: list[str]) -> str:
    known = ", ".join(sorted(cls.option_names or ())) or "none"
    return f"unknown option {', '.join(repr(u) for u in unknown)} for {cls.protocol}; known: {known}"


class Device(ABC):
    """Common part of every driver."""

    kind: ClassVar[str] = ""          # "balance" | "tachometer" | "motor" | "strobe"
    protocol: ClassVar[str] = ""      # registry name, e.g. "mtsics"
    #: serial settings the real device ships with (e.g. A&D: 2400 7E1)
    default_serial: ClassVar[dict[str, Any]] = {"baudrate": 9600}

    #: the option names the driver understands (rig file ``options``, ``labkit probe -o``);
    #: None: not declared, anything is accepted
    option_names: ClassVar[frozenset[str] | None] = None

    def __init__(self, port: serial.SerialBase, clock: Clock, name: str = "", **options: Any):
        unknown = unknown_options(type(self), options)
        if unknown:
            raise ValueError(unknown_options_message(type(self), unknown))
        self.port = port
        self.clock = clock
        self.name = name or self.protocol
        self.options = options
        self.last_bytes = b""  # tail of what was last received, for error messages

    def identify(self) -> dict[str, Any]:
        """Whatever the protocol tells about the device (model, serial, firmware); may be {}."""
        return {}

    def close(self) -> None:
        """Release the device (motors: command zero first). Closes the port."""
        try:
            self.port.close()
        except Exception:  # noqa: BLE001 - closing a dead port must not mask the real error
            pass

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Balance(Device):
    """A balance or load cell. Readings are force (N) when the unit allows, else mass (kg)."""

    kind = "balance"

    @abstractmethod
    def read(self, timeout: float = 2.0) -> Reading:
        """The next reading, stable or not (MT-SICS ``SI``, A&D ``Q``, stream latest)."""

    def read_stable(self, timeout: float = 20.0) -> Reading:
        """The next stable reading (MT-SICS ``S``); default: poll ``read`` until stable."""
        deadline = self.clock.now() + timeout
        while True:
            reading = self.read(timeout=max(0.1, deadline - self.clock.now()))
            if reading.stable and not reading.overload:
                return reading
            if self.clock.now() >= deadline:
                from labkit.errors import DeviceTimeout

                raise DeviceTimeout(self.name, "read_stable", reading.raw, "no stable reading")
            self.clock.sleep(0.05)

    @abstractmethod
    def zero(self, timeout: float = 20.0) -> None:
        """Set zero (MT-SICS ``Z``, A&D ``Z``, HX711 ``t``)."""

    def tare(self, timeout: float = 20.0) -> None:
        """Tare; defaults to zero for devices without a separate tare."""
        self.zero(timeout)


class Tachometer(Device):
    """A streaming tachometer. A reader (thread on a real clock) keeps the latest readings."""

    kind = "tachometer"

    @abstractmethod
    def latest(self) -> Reading | None:
        """The newest angular-speed reading (rad/s), or None before the first one."""

    @abstractmethod
    def readings_since(self, t: float) -> list[Reading]:
        """All readings received at clock time > t, oldest first."""

    def wait_reading(self, timeout: float = 2.0) -> Reading:
        """Block (on the clock) until a reading newer than now arrives."""
        start = self.clock.now()
        while True:
            new = self.readings_since(start)
            if new:
                return new[-1]
            if self.clock.now() - start >= timeout:
                from labkit.errors import DeviceTimeout

                raise DeviceTimeout(self.name, "stream", self.last_bytes, f"no reading in {timeout} s")
            self.clock.sleep(0.01)


class MotorController(Device):
    """A motor PWM/speed controller. Never starts a motor on open.

    Implementations refresh the setpoint at >= 20 Hz (``clock.every``) once the motor is
    enabled, and command zero/brake on ``stop()``, ``close()`` and any exception.
    """

    kind = "motor"
    supports_speed_command: ClassVar[bool] = False
    #: why the last ``stop()`` could not be delivered (a dead port); None when it was, or when
    #: the driver cannot tell (labkit.devices.motor.keepalive sets it)
    stop_error: str | None = None

    @abstractmethod
    def enable(self) -> None:
        """Allow motion (SMC: exit safe start). Only protocols/runners call this, never probe."""

    @abstractmethod
    def set_duty(self, duty: float) -> None:
        """Target duty cycle in -1..1 (sign = direction)."""

    def set_speed(self, speed_rad_s: float) -> None:
        """Closed-loop speed in the controller (VESC SET_RPM). Not all controllers can."""
        raise NotImplementedError(f"{self.protocol} has no speed command; use labkit.control")

    @abstractmethod
    def stop(self) -> None:
        """Command zero (brake where the protocol has it). Must not raise on a dead port."""

    @abstractmethod
    def status(self) -> MotorStatus:
        """Read status/variables (errors, duty, speed where known). Never starts the motor."""

    def close(self) -> None:
        try:
            self.stop()
        finally:
            super().close()
