"""Measurement protocols and their runner (see runner.py, events.py, docs/reference/protocols.md)."""

from __future__ import annotations

from labkit.errors import LabkitError
from labkit.hints import Column, Curve, Hints, ReportFit
from labkit.protocols.cone_sweep import ConeSweep
from labkit.protocols.events import EventBus, ListSink, ProgressSink, Sink
from labkit.protocols.runner import ProtocolDef, RunContext, Runner, RunOutcome, Step, StopRequested
from labkit.protocols.speed_sweep import SpeedSweep
from labkit.protocols.spin_critical import SpinCritical
from labkit.protocols.strobe_sweep import StrobeSweep

PROTOCOLS: dict[str, type[ProtocolDef]] = {
    p.name: p for p in (SpeedSweep, SpinCritical, ConeSweep, StrobeSweep)}


def get_protocol(name: str) -> ProtocolDef:
    """A fresh protocol object by name (built in, or a ``labkit.protocols`` entry point:
    :mod:`labkit.plugins`); LabkitError listing the known ones otherwise."""
    if name not in PROTOCOLS:
        from labkit.plugins import load_protocol_plugins, problems_note

        load_protocol_plugins(PROTOCOLS, ProtocolDef)
        if name not in PROTOCOLS:
            import difflib

            close = difflib.get_close_matches(name, sorted(PROTOCOLS), n=1, cutoff=0.6)
            guess = f" (did you mean {close[0]!r}?)" if close else ""
            raise LabkitError(f"unknown protocol {name!r}{guess}; known: {', '.join(sorted(PROTOCOLS))}"
                              + problems_note())
    return PROTOCOLS[name]()


#: :mod:`labkit.protocols.launch` (which imports this package) is reached through the package
_LAUNCH = ("execute", "prepare_run", "replay_session")

__all__ = [
    "PROTOCOLS", "Column", "Curve", "EventBus", "Hints", "ListSink", "ProgressSink", "ProtocolDef",
    "ReportFit",
    "RunContext", "RunOutcome", "Runner", "Sink", "SpeedSweep", "SpinCritical", "Step", "StopRequested",
    "execute", "get_protocol", "prepare_run", "replay_session",
]


def __getattr__(name: str):
    if name in _LAUNCH:
        from labkit.protocols import launch

        return getattr(launch, name)
    raise AttributeError(f"module 'labkit.protocols' has no attribute {name!r}")
