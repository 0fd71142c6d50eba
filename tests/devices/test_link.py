"""labkit.devices.link: the transport every driver talks through, on a pyserial loop:// port
(bytes written come back as bytes to read) and a virtual clock."""

from __future__ import annotations

import pytest
import serial

from labkit.devices.link import PacketLink, ReplyQueue
from labkit.errors import DeviceDisconnected, DeviceError, DeviceTimeout
from labkit.io.clock import VirtualClock


@pytest.fixture
def loop_port():
    port = serial.serial_for_url("loop://", timeout=0)
    yield port
    port.close()


def test_packet_link_reads_exactly_the_reply(loop_port):
    link = PacketLink(loop_port, VirtualClock(), "rotor_motor")
    link.write(b"\x01\x02\x03", "GET")
    assert link.read_exact(3, 0.1, "GET") == b"\x01\x02\x03"
    assert link.last_bytes == b"\x01\x02\x03"


def test_packet_link_timeout_and_garbled_reply_name_device_command_and_bytes(loop_port):
    link = PacketLink(loop_port, VirtualClock(), "rotor_motor")
    link.write(b"\x01", "GET")
    with pytest.raises(DeviceTimeout) as info:
        link.read_exact(4, 0.1, "GET")
    assert "rotor_motor" in str(info.value) and "1 of 4 reply bytes in 0.1 s" in str(info.value)
    link.write(b"\x01\x02\x03", "GET")
    with pytest.raises(DeviceError) as garbled:
        link.read_exact(2, 0.1, "GET", quiet_s=0.01)
    assert "garbled reply: 3 bytes where 2 were expected" in str(garbled.value)


def test_a_closed_port_is_a_disconnect_naming_the_command(loop_port):
    link = PacketLink(loop_port, VirtualClock(), "rotor_motor")
    loop_port.close()
    with pytest.raises(DeviceDisconnected) as info:
        link.write(b"\x00", "SET_DUTY 0.5000")
    assert "SET_DUTY 0.5000" in str(info.value)


def test_reply_queue_waits_on_the_clock_and_reports_a_timeout(loop_port):
    clock = VirtualClock()
    checks = []
    queue = ReplyQueue(loop_port, clock, "rotor_tach", check=lambda: checks.append(clock.now()),
                       tail=lambda: b"")
    assert queue.wait(bool, 0.05) is False
    assert clock.now() >= 0.05 and checks        # the reader was asked while waiting
    queue.put(b"OK")
    assert queue.wait(bool, 0.05) is True and list(queue.replies) == [b"OK"]
