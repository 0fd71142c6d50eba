"""User protocols and drivers from installed packages (entry points; docs/how-to/add-a-protocol.md).

A package declares, in its pyproject.toml::

    [project.entry-points."labkit.protocols"]
    torque-sweep = "mylab.protocols:TorqueSweep"      # a labkit.protocols.ProtocolDef subclass

    [project.entry-points."labkit.drivers"]
    my-balance = "mylab.balance:MyBalance"            # a labkit.devices.base.Device subclass
                                                      # with kind and protocol set

``labkit run RIG torque-sweep`` and a rig file with ``protocol = "my_balance"`` then find them.
Entry points are read once, on the first lookup that the built-in names do not answer, so a
plain ``labkit run`` pays nothing. A plugin that fails to load is never fatal to the built-in
names; its reason is kept in :data:`PROBLEMS` and shown in the "unknown protocol/driver" error.
"""

from __future__ import annotations

from importlib.metadata import entry_points
from typing import Any

from labkit.device_kinds import canonical_kind

PROTOCOL_GROUP = "labkit.protocols"
DRIVER_GROUP = "labkit.drivers"

#: ``group:name (dist): reason`` of every entry point that could not be used
PROBLEMS: list[str] = []
_loaded: set[str] = set()


def _where(ep: Any) -> str:
    dist = getattr(getattr(ep, "dist", None), "name", None)
    return f"{ep.group}:{ep.name}" + (f" ({dist})" if dist else "")


def _load_group(group: str) -> list[tuple[Any, Any]]:
    """``(entry point, loaded object)`` of every loadable entry point of ``group`` (once)."""
    if group in _loaded:
        return []
    _loaded.add(group)
    out = []
    for ep in entry_points(group=group):
        try:
            out.append((ep, ep.load()))
        except Exception as exc:  # a user's package: any import error is its problem, reported
            PROBLEMS.append(f"{_where(ep)}: cannot load {ep.value} ({type(exc).__name__}: {exc})")
    return out


def load_protocol_plugins(registry: dict[str, Any], base: type) -> None:
    """Add the ``labkit.protocols`` entry points to ``registry`` (name -> subclass of ``base``,
    labkit.protocols.ProtocolDef: passed in, so this module imports no protocol or driver code)."""
    for ep, obj in _load_group(PROTOCOL_GROUP):
        if not (isinstance(obj, type) and issubclass(obj, base) and getattr(obj, "name", "")):
            PROBLEMS.append(f"{_where(ep)}: {ep.value} is not a ProtocolDef subclass with a name")
            continue
        if obj.name in registry and registry[obj.name] is not obj:
            PROBLEMS.append(f"{_where(ep)}: protocol {obj.name!r} already exists; not replaced")
            continue
        registry[obj.name] = obj


def load_driver_plugins(registry: dict[tuple[str, str], Any], base: type) -> None:
    """Add the ``labkit.drivers`` entry points to ``registry`` ((kind, protocol) -> subclass of
    ``base``, labkit.devices.base.Device, with kind and protocol set)."""
    for ep, obj in _load_group(DRIVER_GROUP):
        if not (isinstance(obj, type) and issubclass(obj, base) and getattr(obj, "protocol", "")
                and getattr(obj, "kind", "")):
            PROBLEMS.append(f"{_where(ep)}: {ep.value} is not a Device subclass with kind and protocol")
            continue
        kind = canonical_kind(obj.kind)  # a plugin written with kind = "tach" is a tachometer
        existing = registry.get((kind, obj.protocol))
        if existing is not None and existing is not obj:
            PROBLEMS.append(f"{_where(ep)}: {kind} driver {obj.protocol!r} already exists; not replaced")
            continue
        registry[(kind, obj.protocol)] = obj


def problems_note() -> str:
    """``; plugins not loaded: ...`` for an error message (empty when every plugin loaded)."""
    return f"; plugins not loaded: {'; '.join(PROBLEMS)}" if PROBLEMS else ""
