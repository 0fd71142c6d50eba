"""labkit.devices: one small driver class per real protocol (docs/reference/devices-balance.md,
docs/reference/devices-tach-motor.md).

A driver takes an *open* port (:func:`labkit.io.open_port`) and a clock and returns
:class:`Reading` s (SI inside; ``flags`` say what else the driver noticed, ``raw`` the bytes).
Drivers are found by kind and protocol name::

    Balance = driver_class("balance", "mtsics")
    with Balance(open_port("/dev/ttyUSB0", baudrate=9600, timeout=0.5), RealClock()) as balance:
        print(balance.read_stable())

The driver modules (:mod:`labkit.devices.balance`, ``.motor``, ``.tachometer``) load on the
first :func:`driver_class` / :func:`known_drivers` call.
"""

from labkit.devices.base import Balance, Device, MotorController, MotorStatus, Tachometer
from labkit.devices.registry import driver_class, known_drivers, register_driver
from labkit.readings import Reading

__all__ = ["Balance", "Device", "MotorController", "MotorStatus", "Reading", "Tachometer", "driver_class",
           "known_drivers", "register_driver"]
