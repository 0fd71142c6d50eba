"""Opening a rig: ports (optionally recorded into a session's cassettes) and live drivers.

:func:`open_rig` opens every port of a :class:`~labkit.rig.config.Rig` and instantiates its
drivers; :class:`OpenRig` gives them back by role and kind (``balance(role)``,
``tachometer(role)``, ``motor(role)``, ``camera(role)``, ``strobe(role)``) and closing it commands
every motor to zero first.
"""

from __future__ import annotations

import urllib.parse
from collections.abc import Callable
from pathlib import Path
from typing import Any

from labkit.control.handle import RigMotor
from labkit.control.stopping import stop_motor
from labkit.devices.base import Balance, MotorController, Tachometer
from labkit.devices.camera import Camera, open_camera
from labkit.devices.registry import driver_class
from labkit.devices.strobe.labkit_strobe import Strobe
from labkit.io.ports import open_port
from labkit.rig.checks import check_role
from labkit.rig.config import DeviceConfig, Rig

PortOpener = Callable[..., Any]


def _record_url(inner: str, cassette: Path, role: str) -> str:
    check_role("<rig>", f"devices.{role}", role)  # a Rig built in Python skips load_rig's check
    query = urllib.parse.urlencode({"cassette": str(cassette), "port": role})
    return f"record://{inner}?{query}" if "?" not in inner else f"record://{inner}&{query}"


class OpenRig:
    """A rig with open ports and live drivers, by role. ``close()`` zeroes motors first.

    ``devices[role]`` is the driver for balances and tachometers and a rig-aware
    :class:`labkit.control.handle.RigMotor` for motors (speeds within the rig's limits and
    interlocks); ``devices[role].raw_driver`` (or ``drivers[role]``) is the bare motor driver.
    """

    def __init__(self, rig: Rig, clock: Any) -> None:
        self.rig = rig
        self.clock = clock
        self.drivers: dict[str, Any] = {}
        self.port_urls: dict[str, str] = {}
        self.stop_failures: dict[str, str] = {}
        self._handles: dict[str, Any] = {}

    @property
    def devices(self) -> dict[str, Balance | Tachometer | RigMotor]:
        """Every device by role (motors as rig-aware handles)."""
        out: dict[str, Balance | Tachometer | RigMotor] = {}
        for role, driver in self.drivers.items():
            if self.rig.devices[role].kind == "motor":
                out[role] = self.motor(role)
            else:
                out[role] = driver
        return out

    # ---- typed accessors, by kind ---------------------------------------------------------
    def _of_kind(self, role: str, kind: str) -> Any:
        dev = self.rig.devices.get(role)
        if dev is None or dev.kind != kind or role not in self.drivers:
            have = ", ".join(sorted(r for r, d in self.rig.devices.items() if d.kind == kind)) or "none"
            raise KeyError(f"rig {self.rig.name!r} has no open {kind} called {role!r} ({kind}s: {have})")
        return self.drivers[role]

    def balance(self, role: str) -> Balance:
        """The balance driver ``role`` (KeyError naming the rig's balances if there is none)."""
        return self._of_kind(role, "balance")

    def tachometer(self, role: str) -> Tachometer:
        """The tachometer driver ``role``."""
        return self._of_kind(role, "tachometer")

    def strobe(self, role: str) -> Strobe:
        """The stroboscope driver ``role`` (device kind ``strobe``, docs/reference/devices-strobe.md)."""
        return self._of_kind(role, "strobe")

    def motor(self, role: str) -> RigMotor:
        """The rig-aware handle of motor ``role`` (speeds within the rig's limits and interlocks)."""
        self._of_kind(role, "motor")
        return self._handles.setdefault(role, RigMotor(self, role))

    def camera(self, role: str) -> Camera:
        """The camera ``role`` (:mod:`labkit.devices.camera`)."""
        return self._of_kind(role, "camera")

    def cameras(self) -> dict[str, Camera]:
        return {r: d for r, d in self.drivers.items() if self.rig.devices[r].kind == "camera"}

    def balances(self) -> dict[str, Balance]:
        return {r: d for r, d in self.drivers.items() if self.rig.devices[r].kind == "balance"}

    def tachometers(self) -> dict[str, Tachometer]:
        return {r: d for r, d in self.drivers.items() if self.rig.devices[r].kind == "tachometer"}

    def motors(self) -> dict[str, MotorController]:
        """The motor drivers themselves (raw), by role."""
        return {r: d for r, d in self.drivers.items() if self.rig.devices[r].kind == "motor"}

    def stop_motors(self) -> list[str]:
        """Command every motor to zero; never raises. Returns the roles whose STOP was not
        delivered (their reason is in ``stop_failures``)."""
        failed = []
        for role, motor in self.motors().items():
            problem = stop_motor(motor)
            if problem:
                self.stop_failures[role] = problem
                failed.append(role)
        return failed

    def close(self) -> None:
        for handle in self._handles.values():
            if handle._control is not None:
                handle._control.stop("rig closed")
        self.stop_motors()
        for role in sorted(self.drivers, key=lambda r: self.rig.devices[r].kind != "motor"):
            try:
                self.drivers[role].close()
            except Exception:  # noqa: BLE001 - closing must reach every device
                pass
        self.drivers.clear()

    def __enter__(self) -> OpenRig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_rig(rig: Rig, clock: Any, record_to: str | Path | None = None,
             port_override: Callable[[DeviceConfig], str] | None = None) -> OpenRig:
    """Open every port of ``rig`` and instantiate its drivers.

    ``record_to``: a cassette folder; each port is wrapped as
    ``record://<url>?cassette=<folder>/<role>.jsonl&port=<role>``. ``port_override(dev)``
    may replace a device's URL (``labkit replay`` points ports at ``replay://`` cassettes).
    If anything fails, everything already opened is closed (motors zeroed) and the error
    is re-raised.
    """
    opened = OpenRig(rig, clock)
    try:
        for role, dev in rig.devices.items():
            url = port_override(dev) if port_override else dev.port
            if record_to is not None:
                url = _record_url(url, Path(record_to) / f"{role}.jsonl", role)
            if dev.kind == "camera":  # not a serial port: a frame source (labkit.devices.camera)
                opened.port_urls[role] = url
                opened.drivers[role] = open_camera(url, clock, name=role, **dev.options)
                continue
            cls = driver_class(dev.kind, dev.protocol)
            settings = {**getattr(cls, "default_serial", {}), **dev.serial}
            port = open_port(url, clock=clock, **settings)
            opened.port_urls[role] = url
            opened.drivers[role] = cls(port, clock, name=role, **dev.options)
    except BaseException:
        opened.close()
        raise
    return opened
