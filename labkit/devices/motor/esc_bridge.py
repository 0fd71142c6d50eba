"""The labkit hobby-ESC bridge
(docs/reference/devices-tach-motor.md#esc_bridge-hobby-esc-through-the-labkit-arduino-bridge,
``firmware/labkit_esc_bridge``).

An Arduino turns a Pololu-SMC compact-protocol subset into RC servo pulses for an ESC:
``83`` exit safe start, ``85`` speed 0..3200 -> 1000..2000 us, ``86`` (reverse) -> 1000 us,
``92`` brake and ``E0`` stop -> 1000 us, ``A1`` Get Variable 0/20/21/23/127. No CRC, no
device number, no firmware-version command. The bridge has SMC-like safe start and a
500 ms serial command timeout that drops the pulse to 1000 us. ESCs give no feedback:
speed comes from a tachometer.
"""

from __future__ import annotations

from typing import Any, ClassVar

from labkit.devices.motor.pololu_smc import (
    VAR_ERROR_STATUS,
    VAR_INPUT_VOLTAGE,
    VAR_SPEED,
    VAR_TARGET_SPEED,
    PololuSmc,
)
from labkit.devices.registry import register_driver


@register_driver
class EscBridge(PololuSmc):
    """The SMC driver restricted to what the bridge sketch speaks (one direction, compact)."""

    protocol = "esc_bridge"
    default_serial = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}
    status_variables: ClassVar[tuple[int, ...]] = (
        VAR_ERROR_STATUS, VAR_TARGET_SPEED, VAR_SPEED, VAR_INPUT_VOLTAGE)
    allow_reverse: ClassVar[bool] = False
    has_firmware_version: ClassVar[bool] = False
    builtin_watchdog_ms = 500.0  # the sketch's serial command timeout (always on)
    watchdog_advice = "the labkit ESC bridge sketch has a fixed 500 ms command timeout"

    def __init__(self, port: Any, clock: Any, name: str = "", **options: Any):
        for unsupported in ("device_number", "crc"):
            if options.get(unsupported) not in (None, "", False, 0, "0", "false"):
                raise ValueError(f"esc_bridge option {unsupported}: the bridge speaks compact, no CRC")
        options = {**options, "device_number": None, "crc": False, "autobaud": False}
        super().__init__(port, clock, name, **options)
