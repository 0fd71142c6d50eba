"""A rig file checked against the code that will run it: driver registry, driver options,
motor watchdogs and emulated (``sim://``) ports, at load time, before any port opens, so a
typo is a ``file:key: reason`` error and not a failed, "resumable" session.

:func:`parse_rig` and :func:`load_rig` are the public entry points (the schema itself is
:mod:`labkit.rig.config`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from labkit.devices.base import unknown_options, unknown_options_message
from labkit.devices.camera.urls import is_camera_url, parse_camera_url
from labkit.devices.registry import driver_class
from labkit.emulators.base import emulator_class
from labkit.emulators.urls import parse_sim_url
from labkit.errors import PortURLError
from labkit.rig.checks import TableSection, rate_problem, read_rig_text
from labkit.rig.config import Rig, find_rig_file, parse_rig_config


class DriverCheck:
    """The :class:`labkit.rig.config.DeviceCheck` of a real run: drivers and emulators."""

    def protocol(self, sec: TableSection, kind: str, protocol: str) -> None:
        try:
            driver_class(kind, protocol)
        except KeyError as exc:
            raise sec.error("protocol", str(exc.args[0])) from None

    def port(self, sec: TableSection, url: str) -> None:
        if is_camera_url(url):  # cameras: the URL's settings are checked whole (docs/reference/camera.md)
            try:
                parse_camera_url(url)
            except PortURLError as exc:
                raise sec.error("port", exc.reason) from None
            return
        if not url.startswith("sim://"):
            return
        try:  # an emulated device is checked whole: emulator, seed, fault names, rates
            spec = parse_sim_url(url)
            emulator_class(spec.protocol)
        except PortURLError as exc:
            raise sec.error("port", exc.reason) from None
        except KeyError as exc:
            raise sec.error("port", str(exc.args[0])) from None
        for name, value in spec.options.items():
            problem = rate_problem(name, value)
            if problem is not None:
                raise sec.error("port", f"{name}={value}: {problem}")

    def options(self, sec: TableSection, kind: str, protocol: str, port: str,
                options: dict[str, Any]) -> None:
        cls = driver_class(kind, protocol)
        unknown = unknown_options(cls, options)
        if unknown:
            raise sec.error(f"options.{unknown[0]}", unknown_options_message(cls, unknown))
        watchdog = getattr(cls, "watchdog_problem", None)  # motors: the controller's own timeout
        if watchdog is not None:
            problem = watchdog(options, required=not port.startswith(("sim://", "replay://")))
            if problem is not None:
                raise sec.error(*problem)


def parse_rig(text: str, file: str = "<rig>", check_protocols: bool = True) -> Rig:
    """Validate rig-file text and build a :class:`~labkit.rig.config.Rig` (SI inside).

    ``check_protocols`` (default): also check drivers, options, watchdogs and ``sim://`` URLs.
    Raises RigFileError.
    """
    return parse_rig_config(text, file, DriverCheck() if check_protocols else None)


def load_rig(path: str | Path, check_protocols: bool = True) -> Rig:
    """Read and validate a rig file. ``path`` may also name a bundled rig (``emulated-fig525``)."""
    p = find_rig_file(path)
    return parse_rig(read_rig_text(p), str(p), check_protocols)
