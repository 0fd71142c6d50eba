"""Measurement protocols and their runner (see runner.py, events.py, docs/protocols.md)."""

from __future__ import annotations

from labkit.errors import LabkitError
from labkit.protocols.events import EventBus, ListSink, ProgressSink, Sink
from labkit.protocols.runner import ProtocolDef, RunContext, Runner, RunOutcome, Step, StopRequested
from labkit.protocols.speed_sweep import SpeedSweep
from labkit.protocols.spin_critical import SpinCritical

PROTOCOLS: dict[str, type[ProtocolDef]] = {p.name: p for p in (SpeedSweep, SpinCritical)}


def get_protocol(name: str) -> ProtocolDef:
    """A fresh protocol object by name; LabkitError listing the known ones otherwise."""
    try:
        return PROTOCOLS[name]()
    except KeyError:
        raise LabkitError(f"unknown protocol {name!r}; known: {', '.join(sorted(PROTOCOLS))}") from None


__all__ = [
    "PROTOCOLS", "EventBus", "ListSink", "ProgressSink", "ProtocolDef", "RunContext", "RunOutcome",
    "Runner", "Sink", "SpeedSweep", "SpinCritical", "Step", "StopRequested", "get_protocol",
]
