"""PtyHost: an emulator on a real pseudo-terminal, opened with plain pyserial."""

from __future__ import annotations

import threading

import pytest
import serial

from labkit.io.clock import RealClock
from labkit.io.pty_host import PtyHost
from labkit.io.sim_port import build_emulator


def test_plain_pyserial_talks_to_an_emulator_on_a_pty():
    with PtyHost(build_emulator("sim://test_echo?latency=0.01"), clock=RealClock()) as host:
        assert host.path.startswith("/dev/pts/")
        with serial.Serial(host.path, 9600, timeout=2.0) as port:
            assert port.read_until(b"\n") == b"READY\r\n"
            port.write(b"over a pty\n")
            assert port.read_until(b"\n") == b"ECHO over a pty\r\n"


def test_unplug_fails_real_io_and_replug_appears_under_a_new_path():
    reconnected = threading.Event()
    new_paths: list[str] = []

    def on_reconnect(path: str) -> None:
        new_paths.append(path)
        reconnected.set()

    emulator = build_emulator("sim://test_echo?faults=disconnect_at:0.3,reconnect_after:0.3")
    with PtyHost(emulator, clock=RealClock(), on_reconnect=on_reconnect) as host:
        first = host.path
        port = serial.Serial(first, 9600, timeout=2.0)
        assert port.read_until(b"\n") == b"READY\r\n"
        with pytest.raises(serial.SerialException, match="device reports readiness"):
            for _ in range(100):  # the read that spans the unplug must fail, not return b""
                port.read(1)
        port.close()
        assert reconnected.wait(5.0)
        assert new_paths == [host.path] and host.path != first
        assert host.paths == [first, host.path]
        with serial.Serial(host.path, 9600, timeout=2.0) as again:
            assert again.read_until(b"\n") == b"READY\r\n"
            again.write(b"hi\n")
            assert again.read_until(b"\n") == b"ECHO hi\r\n"
