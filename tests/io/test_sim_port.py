"""sim:// ports: emulators behind pyserial's interface, on virtual and real clocks."""

from __future__ import annotations

import pytest
import serial

from labkit.emulators.base import DISCONNECT_MESSAGE
from labkit.errors import PortURLError
from labkit.io.clock import RealClock, VirtualClock, use_clock
from labkit.io.ports import open_port


def test_reply_arrives_after_its_latency_on_the_virtual_clock():
    clock = VirtualClock()
    port = open_port("sim://test_echo?latency=0.25", clock=clock, timeout=1.0)
    assert port.read_until(b"\n") == b"READY\r\n"
    assert clock.now() == 0.0
    port.write(b"hello\n")
    assert port.read_until(b"\n") == b"ECHO hello\r\n"
    assert clock.now() == pytest.approx(0.25)


def test_read_with_nothing_coming_times_out_exactly_on_the_clock():
    clock = VirtualClock(start=10.0)
    port = open_port("sim://test_echo", clock=clock, timeout=0.7)
    port.reset_input_buffer()
    assert port.read(5) == b""
    assert clock.now() == pytest.approx(10.7)


def test_in_waiting_counts_only_bytes_that_are_due():
    clock = VirtualClock()
    port = open_port("sim://test_echo?latency=0.5", clock=clock, timeout=0)
    port.reset_input_buffer()
    port.write(b"x\n")
    assert port.in_waiting == 0
    clock.advance(0.5)
    assert port.in_waiting == len(b"ECHO x\r\n")


def test_streaming_emulator_lines_arrive_at_their_times():
    clock = VirtualClock()
    port = open_port("sim://test_ticker?period=0.1", clock=clock, timeout=1.0)
    lines = [(port.read_until(b"\n"), round(clock.now(), 9)) for _ in range(3)]
    assert lines == [(b"T 1\r\n", 0.1), (b"T 2\r\n", 0.2), (b"T 3\r\n", 0.3)]


def test_open_port_uses_the_current_clock_by_default():
    clock = VirtualClock(start=5.0)
    with use_clock(clock):
        port = open_port("sim://test_echo?latency=1.5", timeout=3.0)
    port.reset_input_buffer()
    port.write(b"a\n")
    assert port.read_until(b"\n") == b"ECHO a\r\n"
    assert clock.now() == pytest.approx(6.5)


def test_disconnect_raises_pyserials_unplug_error_on_every_operation():
    clock = VirtualClock()
    port = open_port("sim://test_echo?faults=disconnect_at:1", clock=clock, timeout=5.0)
    port.reset_input_buffer()
    with pytest.raises(serial.SerialException) as caught:
        port.read(1)  # nothing comes; the unplug at t=1 ends the wait
    assert str(caught.value) == DISCONNECT_MESSAGE
    assert clock.now() == pytest.approx(1.0)
    for operation in (lambda: port.in_waiting, lambda: port.write(b"x\n"), lambda: port.read(1)):
        with pytest.raises(serial.SerialException, match="device reports readiness"):
            operation()


def test_handle_stays_dead_after_reconnect_until_reopened_then_device_has_power_cycled():
    clock = VirtualClock()
    port = open_port(
        "sim://test_echo?faults=disconnect_at:1,reconnect_after:2", clock=clock, timeout=0.1
    )
    assert port.read_until(b"\n") == b"READY\r\n"
    clock.advance(1.5)
    with pytest.raises(serial.SerialException):
        _ = port.in_waiting
    port.close()
    with pytest.raises(serial.SerialException, match="could not open port"):
        port.open()  # still unplugged at t=1.5
    clock.advance(2.0)
    with pytest.raises(serial.SerialException):
        port.read(1)  # the old handle does not come back by itself
    port.close()
    port.open()
    assert port.read_until(b"\n") == b"READY\r\n"  # power-on banner again
    port.write(b"back\n")
    assert port.read_until(b"\n") == b"ECHO back\r\n"


def test_wrong_serial_settings_garble_bytes_both_ways():
    clock = VirtualClock()
    right = open_port("sim://test_7e1?seed=1", clock=clock, timeout=0.5,
                      baudrate=2400, bytesize=7, parity="E")
    assert right.read_until(b"\n") == b"READY\r\n"
    wrong = open_port("sim://test_7e1?seed=1", clock=clock, timeout=0.5, baudrate=9600)
    banner = wrong.read(7)
    assert len(banner) == 7 and banner != b"READY\r\n"
    wrong.write(b"hello\n")  # garbled on the way in: the device never sees a line
    assert b"ECHO hello" not in wrong.read(100)


def test_sim_port_works_on_the_real_clock():
    port = open_port("sim://test_echo?latency=0.02", clock=RealClock(), timeout=1.0)
    assert port.read_until(b"\n") == b"READY\r\n"
    port.write(b"real\n")
    assert port.read_until(b"\n") == b"ECHO real\r\n"


def test_bad_sim_urls_name_the_url_and_problem():
    with pytest.raises(PortURLError, match="no emulator 'nope'"):
        open_port("sim://nope", clock=VirtualClock())
    with pytest.raises(PortURLError, match="seed='x' is not an integer"):
        open_port("sim://test_echo?seed=x", clock=VirtualClock())
    with pytest.raises(PortURLError, match="'abc' is not a number"):
        open_port("sim://test_echo?faults=delay:abc", clock=VirtualClock())
    # a mistyped fault would otherwise run a clean emulator and the fault test would test nothing
    with pytest.raises(PortURLError, match="unknown fault 'garbge'; known: delay, "):
        open_port("sim://test_echo?faults=garbge:0.1", clock=VirtualClock())
    with pytest.raises(PortURLError, match="unknown fault 'unplug'"):
        open_port("sim://test_echo?faults=unplug", clock=VirtualClock())


def test_native_urls_still_open():
    port = open_port("loop://", timeout=0.1)
    port.write(b"abc")
    assert port.read(3) == b"abc"
