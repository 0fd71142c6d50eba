"""Measurement protocols and their runner (see runner.py, events.py, docs/reference/protocols.md)."""

from __future__ import annotations

from labkit.hints import Column, Curve, Hints, ReportFit
from labkit.protocols.cone_sweep import ConeSweep
from labkit.protocols.context import RunContext, StopRequested
from labkit.protocols.definition import ProtocolDef, Step
from labkit.protocols.events import EventBus, ListSink, ProgressSink, Sink
from labkit.protocols.registry import PROTOCOLS, get_protocol
from labkit.protocols.runner import Runner, RunOutcome
from labkit.protocols.speed_sweep import SpeedSweep
from labkit.protocols.spin_critical import SpinCritical
from labkit.protocols.strobe_sweep import StrobeSweep

#: running and replaying are imported on first use (they bring the rig, the session, the devices)
_LAZY = {"execute": "labkit.protocols.launch", "prepare_run": "labkit.protocols.launch",
         "replay_session": "labkit.protocols.replay"}

__all__ = [
    "PROTOCOLS", "Column", "ConeSweep", "Curve", "EventBus", "Hints", "ListSink", "ProgressSink",
    "ProtocolDef", "ReportFit",
    "RunContext", "RunOutcome", "Runner", "Sink", "SpeedSweep", "SpinCritical", "Step", "StopRequested",
    "StrobeSweep",
    "execute", "get_protocol", "prepare_run", "replay_session",
]


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'labkit.protocols' has no attribute {name!r}")
