"""Pololu SMC G2 with "CRC for responses" enabled, against the vendor's user's guide.

Source: Pololu Simple Motor Controller G2 User's Guide (pololu.com/docs/0J77), section 6.5
"Cyclic redundancy check (CRC) error detection" (read 2026-11): "The Simple Motor
Controller G2 will append a CRC byte to the data it transmits in response to serial commands
if CRC is enabled for responses"; the CRC is CRC-7, polynomial 0x91, LSB first, computed by
the guide's sample C code (section 8.13), which ``guide_crc7`` below transcribes.
"""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.cli import main
from labkit.devices.motor.pololu_smc import strip_response_crc
from labkit.devices.registry import driver_class
from labkit.emulators.plant import reset_plants
from labkit.errors import DeviceError
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port


@pytest.fixture(autouse=True)
def _fresh_plants():
    reset_plants()
    yield
    reset_plants()


def guide_crc7(message: bytes) -> int:
    """The user's guide's getCRC(): XOR each byte in, eight shifts with 0x91 on a set LSB."""
    crc = 0
    for byte in message:
        crc ^= byte
        for _ in range(8):
            if crc & 1:
                crc ^= 0x91
            crc >>= 1
    return crc


@pytest.mark.parametrize("data", [bytes.fromhex("40 06"), bytes.fromhex("E0 2E"),
                                  bytes.fromhex("A1 00 04 01"), b"\x00\x00"])
def test_reply_crc_byte_is_checked_and_stripped(data):
    assert strip_response_crc(data + bytes([guide_crc7(data)])) == data
    with pytest.raises(ValueError, match="response CRC"):
        strip_response_crc(data + bytes([guide_crc7(data) ^ 0x01]))


def test_probe_reads_a_controller_with_crc_for_responses(capsys):
    code = main(["probe", "motor", "--protocol", "pololu_smc", "--port",
                 "sim://pololu_smc?crc_responses=1&vin_mv=12300", "--samples", "2", "--json",
                 "-o", "crc_responses=1"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert json.loads(captured.err.splitlines()[0])["firmware"] == "1.04"
    for line in captured.out.splitlines():
        assert json.loads(line)["input_voltage_v"] == pytest.approx(12.3, abs=1e-9)


def test_without_the_option_the_error_names_it(capsys):
    code = main(["probe", "motor", "--protocol", "pololu_smc", "--port",
                 "sim://pololu_smc?crc_responses=1", "--samples", "1"])
    err = capsys.readouterr().err
    assert code == 2
    assert "5 bytes where 4 were expected" in err and "crc_responses=1" in err


def test_emulator_appends_the_guide_crc_and_the_driver_refuses_a_corrupt_one():
    clock = VirtualClock()
    cls = driver_class("motor", "pololu_smc")
    port = open_port("sim://pololu_smc?crc_responses=1&crc=1&device_number=13", clock=clock,
                     timeout=0, **cls.default_serial)
    port.write(bytes.fromhex("AA 0D 21 17") + bytes([guide_crc7(bytes.fromhex("AA 0D 21 17"))]))
    clock.sleep(0.05)
    reply = port.read(16)
    assert len(reply) == 3 and reply[2] == guide_crc7(reply[:2])
    assert int.from_bytes(reply[:2], "little") == 12000      # variable 23: VIN in mV
    port.close()

    class FlipLastByte:
        """Wraps the port so each reply's CRC byte arrives corrupted."""

        def __init__(self, inner):
            self.inner = inner

        def __getattr__(self, name):
            return getattr(self.inner, name)

        def read(self, size=1):
            data = self.inner.read(size)
            return data[:-1] + bytes([data[-1] ^ 0x40]) if len(data) == 3 else data

    port = open_port("sim://pololu_smc?crc_responses=1", clock=clock, timeout=0, **cls.default_serial)
    motor = cls(FlipLastByte(port), clock, name="smc", crc_responses=True)
    with pytest.raises(DeviceError, match="response CRC"):
        motor.get_variable(23)
    motor.close()


@settings(max_examples=300, deadline=None)
@given(st.binary(min_size=1, max_size=8), st.integers(0, 7))
def test_fuzz_any_reply_with_its_crc_is_stripped_and_any_flipped_bit_is_caught(data, bit):
    reply = data + bytes([guide_crc7(data)])
    assert strip_response_crc(reply) == data
    corrupted = bytearray(reply)
    corrupted[-1] ^= 1 << bit
    with pytest.raises(ValueError):
        strip_response_crc(bytes(corrupted))
