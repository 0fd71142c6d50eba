"""labkit.io: time and transport (see ARCHITECTURE.md and docs/io.md).

* :mod:`labkit.io.clock` - ``Clock``, ``RealClock``, ``VirtualClock``, ``current_clock``.
* :mod:`labkit.io.ports` - ``open_port(url, *, clock=None, **serial_settings)``; registers the
  ``sim://``, ``record://`` and ``replay://`` URL handlers with pyserial.
* :mod:`labkit.io.sim_port` - ``SimSerial``, ``build_emulator(url)``.
* :mod:`labkit.io.record_port` / :mod:`labkit.io.replay_port` - cassette recording and replay.
* :mod:`labkit.io.cassette` - the JSONL cassette format, ``load_cassette(path)``.
* :mod:`labkit.io.pty_host` - ``PtyHost(emulator, clock=None, on_reconnect=None)``.
* :mod:`labkit.io.calls` - ``port_call(name)`` annotates traffic with the driver call.
"""
