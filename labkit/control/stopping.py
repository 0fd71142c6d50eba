"""Stopping one motor, the step every safe-state path repeats (docs/explanation/safety.md)."""

from __future__ import annotations

from labkit.devices.kinds import MotorKind


def stop_motor(motor: MotorKind) -> str | None:
    """Command ``motor`` to zero. None when the STOP was delivered, else why not (the driver's
    ``stop_error`` or the exception it raised). Never raises: the caller keeps stopping the others."""
    try:
        motor.stop()
        return getattr(motor, "stop_error", None) or None
    except Exception as exc:  # noqa: BLE001 - a safe-state path must reach every motor
        return str(exc)
