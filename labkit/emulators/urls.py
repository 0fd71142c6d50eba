"""Pure parsing of ``sim://`` URLs (no I/O): which emulator, on which plant, with which faults.

``sim://<protocol>?seed=N&faults=a:1,b:2&plant=NAME&role=ROLE&<emulator options>``
"""

from __future__ import annotations

from dataclasses import dataclass, field

from labkit.emulators.base import parse_faults
from labkit.errors import PortURLError
from labkit.io.urls import split_query, split_scheme


@dataclass(frozen=True)
class SimSpec:
    """What a ``sim://`` URL asks for."""

    protocol: str
    seed: int = 0
    faults: dict[str, float] = field(default_factory=dict)
    plant: str = "default"
    role: str = ""
    options: dict[str, str] = field(default_factory=dict)


def parse_sim_url(url: str) -> SimSpec:
    """Parse ``sim://<protocol>?seed=..&faults=..&plant=..&role=..&<options>``."""
    scheme, rest = split_scheme(url)
    if scheme != "sim":
        raise PortURLError(url, "expected a sim://<protocol>?... URL")
    protocol, query = split_query(rest)
    protocol = protocol.strip("/")
    if not protocol:
        raise PortURLError(url, "no emulator protocol after sim://")
    seed, faults, plant, role = 0, {}, "default", ""
    options: dict[str, str] = {}
    for key, value in query:
        if key == "seed":
            try:
                seed = int(value)
            except ValueError:
                raise PortURLError(url, f"seed={value!r} is not an integer") from None
        elif key == "faults":
            try:
                faults.update(parse_faults(value))
            except ValueError as exc:
                raise PortURLError(url, str(exc)) from None
        elif key == "plant":
            plant = value or "default"
        elif key == "role":
            role = value
        else:
            options[key] = value
    return SimSpec(protocol, seed, faults, plant, role or protocol, options)
