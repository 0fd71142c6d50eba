"""The protocols labkit knows by name: the built-in ones and those installed through the
``labkit.protocols`` entry point (:mod:`labkit.plugins`)."""

from __future__ import annotations

from labkit.errors import LabkitError
from labkit.protocols.cone_sweep import ConeSweep
from labkit.protocols.definition import ProtocolDef
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
