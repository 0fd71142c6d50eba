"""Drivers against strict byte pairs in memory (labkit.testing.expected_protocol): what each
driver writes and how it reads one answer, with no plant, emulator or clock fixture. The
bytes are the vendors' (MT-SICS reference manual, Pololu SMC G2 user's guide), not ours."""

from __future__ import annotations

import pytest

from labkit.devices.balance.mtsics import MtSicsBalance
from labkit.devices.motor.pololu_smc import PololuSmc
from labkit.emulators.motors import _smc_crc7
from labkit.errors import DeviceReplyError, DeviceTimeout
from labkit.testing import ProtocolMismatch, expected_protocol

RESET = (b"@\r\n", b'I4 A "B207696838"\r\n')      # MT-SICS: the driver resets the balance on open


def test_mtsics_stable_weight_in_grams_is_kilograms():
    with expected_protocol(MtSicsBalance, [RESET, (b"S\r\n", b"S S      12.34 g\r\n")]) as balance:
        reading = balance.read_stable()
    assert (reading.quantity, reading.value, reading.unit, reading.stable) == ("mass", 0.01234, "kg", True)
    assert reading.raw == b"S S      12.34 g"


def test_mtsics_zero_then_dynamic_reading():
    with expected_protocol(MtSicsBalance, [RESET, (b"Z\r\n", b"Z A\r\n"),
                                           (b"SI\r\n", b"S D       0.02 g\r\n")]) as balance:
        balance.zero()
        reading = balance.read()
    assert not reading.stable and reading.value == pytest.approx(2e-5)


def test_mtsics_banner_before_a_reply_flags_the_reading_device_reset():
    """A balance that rebooted prints its I4 banner again: the next reading says so."""
    with expected_protocol(MtSicsBalance, [RESET, (b"S\r\n", b'I4 A "B207696838"\r\nS S      1.00 g\r\n'),
                                           (b"S\r\n", b"S S      1.00 g\r\n")]) as balance:
        first, second = balance.read_stable(), balance.read_stable()
    assert "device_reset" in first.flags and "device_reset" not in second.flags


def test_mtsics_overload_reply_is_no_number():
    with expected_protocol(MtSicsBalance, [RESET, (b"SI\r\n", b"S +\r\n")]) as balance:
        reading = balance.read()
    assert reading.overload and reading.value != reading.value and "overload" in reading.flags


def test_mtsics_logical_error_names_device_and_command():
    with expected_protocol(MtSicsBalance, [RESET, (b"S\r\n", b"S I\r\n")], name="balance") as balance:
        with pytest.raises(DeviceReplyError, match="balance") as err:
            balance.read_stable()
    assert "S" in str(err.value)


def test_mtsics_silence_is_a_timeout_not_a_hang():
    with expected_protocol(MtSicsBalance, [RESET, (b"S\r\n", None)]) as balance:
        with pytest.raises(DeviceTimeout):
            balance.read_stable(timeout=1.0)


def test_pololu_never_moves_before_enable_and_stops_on_close():
    """Exit safe start (83), forward at 3200 * 0.5 = 1600 (85 00 32: low 5 bits, then the high 7),
    and close stops the motor (E0) - the rotor stops on every exit path."""
    with expected_protocol(PololuSmc, [(b"\x83", None), (b"\x85\x00\x32", None), (b"\xe0", None)]) as motor:
        motor.enable()
        motor.set_duty(0.5)


def test_pololu_crc_option_appends_the_crc7_byte():
    """0x1A after 83 is the guide's worked example; the stop packet's CRC is the emulator's
    own (written apart from the driver)."""
    with expected_protocol(PololuSmc, [(b"\x83\x1a", None), (bytes([0xE0, _smc_crc7(b"\xe0")]), None)],
                           crc=True) as motor:
        motor.enable()


def test_a_wrong_byte_fails_at_once_naming_both():
    wanted = r"expected the driver to write b'Z\\r\\n', it wrote b'S\\r\\n'"
    with pytest.raises(ProtocolMismatch, match=wanted):
        with expected_protocol(MtSicsBalance, [RESET, (b"Z\r\n", b"Z A\r\n")]) as balance:
            balance.read_stable()


def test_an_exchange_that_never_happens_fails_the_block():
    with pytest.raises(ProtocolMismatch, match="never happened"):
        with expected_protocol(MtSicsBalance, [RESET, (b"S\r\n", b"S S 1.00 g\r\n")]):
            pass
