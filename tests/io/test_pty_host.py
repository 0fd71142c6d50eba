"""PtyHost: an emulator on a real pseudo-terminal, opened with plain pyserial."""

from __future__ import annotations

import threading

import pytest
import serial

from labkit.emulators.sim_port import build_emulator
from labkit.io.clock import RealClock
from labkit.io.pty_host import PtyHost


def lines_until_echo(port: serial.Serial) -> bytes:
    """The first ECHO line, skipping a power-on banner that may or may not have been flushed."""
    line = port.read_until(b"\n")
    return port.read_until(b"\n") if line == b"READY\r\n" else line


def test_plain_pyserial_talks_to_an_emulator_on_a_pty():
    with PtyHost(build_emulator("sim://test_echo?latency=0.01"), clock=RealClock()) as host:
        assert host.path.startswith("/dev/pts/")
        with serial.Serial(host.path, 9600, timeout=2.0) as port:
            # (pyserial flushes input on open: a banner printed before that is lost, as on a wire)
            port.write(b"over a pty\n")
            assert lines_until_echo(port) == b"ECHO over a pty\r\n"


def test_unplug_fails_real_io_and_replug_appears_under_a_new_path():
    reconnected = threading.Event()
    new_paths: list[str] = []

    def on_reconnect(path: str) -> None:
        new_paths.append(path)
        reconnected.set()

    emulator = build_emulator("sim://test_echo?faults=disconnect_at:1.0,reconnect_after:0.3")
    with PtyHost(emulator, clock=RealClock(), on_reconnect=on_reconnect) as host:
        first = host.path
        port = serial.Serial(first, 9600, timeout=2.0)
        port.write(b"before\n")
        assert lines_until_echo(port) == b"ECHO before\r\n"
        with pytest.raises(serial.SerialException, match="device reports readiness"):
            for _ in range(100):  # the read that spans the unplug must fail, not return b""
                port.read(1)
        port.close()
        assert reconnected.wait(5.0)
        assert new_paths == [host.path] and host.path != first
        assert host.paths == [first, host.path]
        assert emulator.power_on_count == 2  # the replugged device power-cycled
        with serial.Serial(host.path, 9600, timeout=2.0) as again:
            again.write(b"hi\n")
            assert lines_until_echo(again) == b"ECHO hi\r\n"


def test_opening_the_pty_at_the_wrong_baud_garbles_both_ways():
    with PtyHost(build_emulator("sim://test_7e1?latency=0.01"), clock=RealClock()) as host:
        with serial.Serial(host.path, 9600, timeout=0.5) as wrong:  # the device expects 2400
            wrong.write(b"hello\n")
            assert b"ECHO hello" not in wrong.read(64)
        with serial.Serial(host.path, 2400, bytesize=7, parity="E", timeout=2.0) as right:
            right.write(b"\nhello\n")  # the LF ends the junk line the device heard before
            lines = [right.read_until(b"\n")]
            while lines[-1] != b"ECHO hello\r\n" and lines[-1] and len(lines) < 8:
                lines.append(right.read_until(b"\n"))
            assert lines[-1] == b"ECHO hello\r\n"
            assert any(x.startswith(b"ECHO ") for x in lines[:-1])  # the junk it heard at 9600
