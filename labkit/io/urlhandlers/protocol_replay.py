"""``replay://<cassette>?mode=strict|timed|faithful``: serve a recorded cassette as a port.

pyserial's hook picks the port class by the URL's mode: strict and timed are
:class:`labkit.io.replay_port.ReplaySerial`, faithful (the real-clock replay, ADR 0019) is
:class:`labkit.io.faithful_port.FaithfulSerial`.
"""

from labkit.io.clocked import ClockedSerial
from labkit.io.replay_port import ReplaySerial
from labkit.io.urls import parse_replay_url

__all__ = ["serial_class_for_url"]


def serial_class_for_url(url: str) -> tuple[str, type[ClockedSerial]]:
    """pyserial hook: the class that serves ``url``."""
    if parse_replay_url(url).mode == "faithful":
        from labkit.io.faithful_port import FaithfulSerial

        return url, FaithfulSerial
    return url, ReplaySerial
