"""A fixed, scripted motor-controller session: what motor cassettes are recorded with.

identify, status, enable, run at ``duty`` for ``run_s`` (20 Hz keep-alive), status, close
(zero). The same script replayed from the cassette must write the same bytes and read the
same statuses.
"""

from __future__ import annotations

from typing import Any, cast

import serial

from labkit.devices.base import MotorController
from labkit.devices.registry import driver_class
from labkit.io.clock import Clock


def run_motor_script(port: serial.SerialBase, clock: Clock, protocol: str, duty: float = 0.3,
                     run_s: float = 1.0, **options: Any) -> dict[str, Any]:
    """Returns ``{"identify": {...}, "statuses": [MotorStatus.as_json(), ...]}``."""
    cls = cast("type[MotorController]", driver_class("motor", protocol))
    statuses = []
    with cls(port, clock, name=f"motor {protocol}", **options) as motor:
        info = motor.identify()
        statuses.append(motor.status().as_json())
        motor.enable()
        motor.set_duty(duty)
        clock.sleep(run_s)
        statuses.append(motor.status().as_json())
    return {"identify": info, "statuses": statuses}
