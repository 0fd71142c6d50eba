"""labkit.io: time and transport (docs/reference/io.md). It knows no emulator and no driver.

* :mod:`labkit.io.clock` - ``Clock``, ``RealClock``, ``VirtualClock``, ``current_clock``, ``use_clock``.
* :mod:`labkit.io.ports` - ``open_port(url, *, clock=None, **serial_settings)``; registers the
  ``record://`` and ``replay://`` URL handlers with pyserial (``sim://`` is registered by
  :mod:`labkit.emulators`).
* :mod:`labkit.io.record_port` / :mod:`labkit.io.replay_port` - cassette recording and replay.
* :mod:`labkit.io.cassette` - the JSONL cassette format, ``load_cassette(path)``.
* :mod:`labkit.io.pty_host` - ``PtyHost(device, clock=None, on_reconnect=None)``: any byte
  device (an emulator) on a real pseudo-terminal.
* :mod:`labkit.io.calls` - ``port_call(name)`` annotates traffic with the driver call.
"""

from labkit.io.calls import port_call
from labkit.io.cassette import Cassette, load_cassette
from labkit.io.clock import Clock, RealClock, VirtualClock, current_clock, use_clock
from labkit.io.ports import open_port, register_url_handlers
from labkit.io.pty_host import PtyHost

__all__ = [
    "Cassette", "Clock", "PtyHost", "RealClock", "VirtualClock", "current_clock", "load_cassette",
    "open_port", "port_call", "register_url_handlers", "use_clock",
]
