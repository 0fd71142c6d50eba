"""The device kinds as typed protocols: what a protocol step or the speed loop may ask of a
balance, a tachometer, a motor controller, a camera and a strobe, checked statically (mypy)
and, by method name, at run time.

The abstract classes of :mod:`labkit.devices.base` (``Balance``, ``Tachometer``,
``MotorController``) satisfy them; so does a plugin driver (``labkit.drivers`` entry point) that
subclasses only ``Device`` but has the methods. :class:`labkit.protocols.context.RunContext`
hands devices out through them (``ctx.balance(role)``, ``ctx.tachometer(role)``,
``ctx.motor(role)``, ``ctx.camera(role)``, ``ctx.strobe(role)``); :mod:`labkit.control.loop`
drives a :class:`MotorKind` from a :class:`TachometerKind`. The kinds' words are in
:mod:`labkit.device_kinds`.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from labkit.devices.base import MotorStatus
from labkit.readings import Reading


@runtime_checkable
class BalanceKind(Protocol):
    """A balance or load cell (kind ``balance``)."""

    name: str

    def read(self, timeout: float = 2.0) -> Reading: ...

    def read_stable(self, timeout: float = 20.0) -> Reading: ...

    def zero(self, timeout: float = 20.0) -> None: ...


@runtime_checkable
class TachometerKind(Protocol):
    """A streaming tachometer (kind ``tachometer``)."""

    name: str

    def latest(self) -> Reading | None: ...

    def readings_since(self, t: float) -> list[Reading]: ...


@runtime_checkable
class MotorStatusKind(Protocol):
    """What a protocol step may ask of a motor controller: its status (errors, duty, speed where
    the controller measures it). Speeds go through ``ctx.set``, the rig's speed loop, within the
    rig's limits and interlocks; so :meth:`RunContext.motor` hands a motor out as this."""

    name: str

    def status(self) -> MotorStatus: ...


@runtime_checkable
class MotorKind(MotorStatusKind, Protocol):
    """A motor controller (kind ``motor``, docs/reference/devices-tach-motor.md): what the speed
    loop (:mod:`labkit.control.loop`) commands. Opening never starts the motor; ``stop`` works
    from any state and never raises on a dead port."""

    def enable(self) -> None: ...

    def set_duty(self, duty: float) -> None: ...

    def stop(self) -> None: ...


@runtime_checkable
class CameraKind(Protocol):
    """A camera (kind ``camera``): bursts of frames at its settings."""

    name: str
    settings: Any

    def burst(self, n: int, step: Any = None) -> list[Any]: ...


@runtime_checkable
class StrobeKind(Protocol):
    """A stroboscope locked to the rotor (kind ``strobe``, docs/reference/devices-strobe.md)."""

    name: str

    def set_offset(self, offset_hz: float) -> None: ...

    def set_divider(self, divider: int) -> None: ...

    def lamp(self, on: bool) -> None: ...

    def statuses_since(self, t: float) -> list[Any]: ...
