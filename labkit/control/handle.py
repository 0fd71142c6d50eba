"""Rig-aware motor handles: what ``open_rig(...).devices["rotor_motor"]`` hands out.

A raw motor driver does whatever it is told: ``set_duty(1.0)`` on the emulated Fig. 6.18 rig
(limit 16 000 RPM, 6 000 RPM/s) ran the rotor to 23 875 RPM with no ramp. A
:class:`RigMotor` only takes speeds, and runs them through the rig's own speed loop
(:mod:`labkit.control.loop`): the rig's ``max_speed`` (refused above it), ``max_ramp``,
the over-speed and tachometer-loss interlocks and the controller's error flags. It stops
the motor on :meth:`stop`, at the end of a ``with`` block (also on an exception) and when
the rig closes.

The driver itself is still there for tests and bring-up, explicitly and without any of the
above: ``handle.raw_driver`` (docs/explanation/safety.md).
"""

from __future__ import annotations

from typing import Any

from labkit.control.loop import SpeedControl, build_speed_control
from labkit.devices.kinds import MotorKind
from labkit.errors import LabkitError, SafetyError
from labkit.units import rad_s_to_rpm, rpm_to_rad_s


class RigMotor:
    """Speed commands for one motor of an open rig, within the rig's limits and interlocks."""

    def __init__(self, opened: Any, role: str) -> None:
        self._opened = opened
        self.role = role
        self.rig = opened.rig
        self.clock = opened.clock
        self.loop = next((lc.name for lc in self.rig.control.loops if lc.motor == role), None)
        self._control: SpeedControl | None = None

    @property
    def raw_driver(self) -> MotorKind:
        """The motor driver itself: no speed limit, no ramp, no interlock. Bring-up and tests only."""
        return self._opened.drivers[self.role]

    @property
    def control(self) -> SpeedControl:
        """The speed loop this handle drives (built on first use)."""
        if self._control is None:
            self._control = build_speed_control(self._opened, self.clock, loops=[self._paired_loop()])
        return self._control

    def _paired_loop(self) -> str:
        """The name of the speed loop that pairs this motor with a tachometer."""
        if self.loop is None:
            raise LabkitError(f"{self.rig.path}: no speed loop pairs {self.role} with a tachometer "
                              "([control] loops), so it cannot be run within the rig's limits; "
                              "use .raw_driver for bring-up")
        return self.loop

    # ---- commands -----------------------------------------------------------------------
    def set_speed(self, speed_rad_s: float) -> None:
        """Target speed in rad/s, ramped at the rig's ``max_ramp``; refused above ``max_speed``."""
        self.control.set_targets({self._paired_loop(): float(speed_rad_s)})

    def set_speed_rpm(self, rpm: float) -> None:
        self.set_speed(rpm_to_rad_s(float(rpm)))

    def hold(self, seconds: float) -> None:
        """Let the loop run ``seconds`` on the rig's clock, checking the interlocks every period;
        raises :class:`SafetyError` (motors already at zero) if one tripped."""
        control = self.control
        end = self.clock.now() + float(seconds)
        while True:
            control.check()
            remaining = end - self.clock.now()
            if remaining <= 0:
                return
            self.clock.sleep(min(control.period_s, remaining))

    def wait_settled(self, timeout_s: float | None = None) -> None:
        """Hold until the speed is within the rig's tolerance for its hold time."""
        control = self.control
        timeout = self.rig.control.settle_timeout_s if timeout_s is None else float(timeout_s)
        end = self.clock.now() + timeout
        while not control.settled():
            control.check()
            if self.clock.now() >= end:
                self.stop()
                raise LabkitError(f"{self.role}: speed did not settle within {timeout:.0f} s; motor at zero")
            self.clock.sleep(control.period_s)

    @property
    def speed_rpm(self) -> float | None:
        """The last measured speed of this motor's loop (None before the first reading)."""
        if self._control is None:
            return None
        measured = self._control.snapshots()[self._paired_loop()].measured_rad_s
        return None if measured is None else rad_s_to_rpm(measured)

    def stop(self) -> None:
        """Every motor of the loop's rig to zero now (never raises)."""
        if self._control is not None:
            self._control.stop("stopped by the caller")
        else:
            self.raw_driver.stop()

    def set_duty(self, duty: float) -> None:
        raise SafetyError(f"{self.role}: set_duty bypasses the rig's limits; use set_speed()/"
                          "set_speed_rpm() (limits and interlocks apply), or .raw_driver.set_duty() "
                          "for bring-up without any")

    # ---- life cycle ---------------------------------------------------------------------
    def __enter__(self) -> RigMotor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def __repr__(self) -> str:
        return f"RigMotor({self.role!r}, loop={self.loop!r})"
