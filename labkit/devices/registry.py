"""The drivers by kind and protocol, and the parsers ``labkit bench io`` times.

A driver module registers its class with :func:`register_driver` (and one sample frame with
:func:`register_parser_benchmark`) when it is imported. The built-in driver packages are an
entry table (:data:`BUILT_IN_DRIVER_PACKAGES`, names imported on the first lookup, as a
plugin's ``labkit.drivers`` entry point is): the drivers import this registry, the registry
imports no driver module by statement (docs/decisions/0028-import-rules-and-sizes.md).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any, Literal, overload

from labkit.device_kinds import canonical_kind
from labkit.devices.base import Balance, Device, MotorController, Tachometer

#: the packages whose import registers labkit's own drivers (loaded by :func:`driver_class`,
#: :func:`known_drivers` and :func:`parser_benchmarks`)
BUILT_IN_DRIVER_PACKAGES = (
    "labkit.devices.camera",
    "labkit.devices.balance",
    "labkit.devices.motor",
    "labkit.devices.strobe",
    "labkit.devices.tachometer",
)

DriverClass = type[Device]
_DRIVERS: dict[tuple[str, str], DriverClass] = {}


def register_driver(cls: DriverClass) -> DriverClass:
    """Class decorator: make ``cls`` findable as ``(cls.kind, cls.protocol)`` (an old kind word,
    ``tach``, registers under its kind, ``tachometer``: labkit.device_kinds)."""
    _DRIVERS[(canonical_kind(cls.kind), cls.protocol)] = cls
    return cls


def load_built_in_drivers() -> None:
    """Import the built-in driver packages (each registers its drivers; imported once)."""
    for name in BUILT_IN_DRIVER_PACKAGES:
        importlib.import_module(name)


@overload
def driver_class(kind: Literal["balance"], protocol: str) -> type[Balance]: ...
@overload
def driver_class(kind: Literal["tachometer", "tach"], protocol: str) -> type[Tachometer]: ...
@overload
def driver_class(kind: Literal["motor"], protocol: str) -> type[MotorController]: ...
@overload
def driver_class(kind: str, protocol: str) -> DriverClass: ...


def driver_class(kind: str, protocol: str) -> DriverClass:
    """Look up a driver; raises KeyError with the known names. A literal kind gives the kind's
    class (``driver_class("motor", ...)`` is a ``type[MotorController]``); ``tach`` is read as
    ``tachometer``."""
    kind = canonical_kind(kind)
    load_built_in_drivers()
    if (kind, protocol) not in _DRIVERS:  # a user's driver (labkit.drivers entry point)?
        from labkit.plugins import load_driver_plugins, problems_note

        load_driver_plugins(_DRIVERS, Device)
        if (kind, protocol) not in _DRIVERS:
            known = sorted(p for k, p in _DRIVERS if k == kind)
            raise KeyError(f"no {kind} driver {protocol!r}; known: {', '.join(known)}{problems_note()}")
    return _DRIVERS[(kind, protocol)]


def known_drivers() -> dict[str, list[str]]:
    load_built_in_drivers()
    out: dict[str, list[str]] = {}
    for kind, protocol in sorted(_DRIVERS):
        out.setdefault(kind, []).append(protocol)
    return out


_PARSER_BENCHMARKS: dict[str, tuple[bytes, Callable[[bytes], Any]]] = {}


def register_parser_benchmark(protocol: str, sample: bytes, parse: Callable[[bytes], Any]) -> None:
    """Offer ``parse(sample)`` (one typical frame/line of ``protocol``) to ``labkit bench io``."""
    _PARSER_BENCHMARKS[protocol] = (sample, parse)


def parser_benchmarks() -> dict[str, tuple[bytes, Callable[[bytes], Any]]]:
    load_built_in_drivers()
    return dict(_PARSER_BENCHMARKS)
