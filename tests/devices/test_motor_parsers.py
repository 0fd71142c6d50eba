"""Motor protocol encoders/decoders against the byte examples of PROTOCOLS 3.1 and 3.2."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.devices.motor.pololu_smc import (
    crc7,
    decode_error_bits,
    duty_to_speed,
    format_command,
    parse_firmware_version,
    parse_variable,
    speed_command,
)
from labkit.devices.motor.vesc import (
    VescFramer,
    crc16_xmodem,
    format_packet,
    format_request,
    format_set_current,
    format_set_duty,
    format_set_rpm,
    parse_packet,
    parse_values,
)

H = bytes.fromhex

# ---- Pololu SMC ----------------------------------------------------------------------------


@pytest.mark.parametrize("data, crc", [(H("83 01"), 0x17), (H("83"), 0x1A), (H("85 00 32"), 0x45),
                                       (H("AA 0D 03"), 0x1C)])
def test_crc7_documented_values(data, crc):
    assert crc7(data) == crc


@pytest.mark.parametrize("speed, data", [(0, H("00 00")), (1600, H("00 32")), (2500, H("04 4E")),
                                         (3200, H("00 64"))])
def test_speed_encoding_examples(speed, data):
    assert speed_command(speed) == (0x85, data)


def test_documented_packets():
    assert format_command(*speed_command(1600)) == H("85 00 32")
    assert format_command(*speed_command(-3200)) == H("86 00 64")
    assert format_command(0x85, H("00 32"), crc=True) == H("85 00 32 45")
    assert format_command(0x83, device_number=13, crc=True) == H("AA 0D 03 1C")
    assert format_command(0x85, H("00 32"), device_number=13) == H("AA 0D 05 00 32")
    assert format_command(0x92, b"\x20") == H("92 20")


def test_variable_replies_from_the_protocol_notes():
    assert parse_variable(H("40 06"), 21) == 1600          # speed
    assert parse_variable(H("E0 2E"), 23) == 12000         # VIN mV
    assert parse_variable(H("FA 00"), 24) == 250           # 25.0 degC
    assert parse_variable(H("C0 F9"), 20) == -1600         # signed target speed


def test_error_bits_and_duty():
    assert decode_error_bits(0b1001) == {"safe_start_violation", "command_timeout"}
    with pytest.raises(ValueError):
        decode_error_bits(1 << 12)
    assert duty_to_speed(0.5) == 1600 and duty_to_speed(-2.0) == -3200


def test_firmware_version_reply():
    assert parse_firmware_version(H("A1 00 04 01")) == {"product_id": 0xA1, "firmware": "1.04"}
    with pytest.raises(ValueError):
        parse_firmware_version(H("A1 00 0F 01"))   # not BCD


@settings(max_examples=300, deadline=None)
@given(st.integers(-3200, 3200))
def test_speed_command_round_trip_and_seven_bit_data(speed):
    cmd, data = speed_command(speed)
    assert all(b < 0x80 for b in data)
    magnitude = data[0] | data[1] << 5
    assert (-magnitude if cmd == 0x86 else magnitude) == speed


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=6))
def test_smc_reply_decoders_never_crash(data):
    for parse in (lambda d: parse_variable(d, 0), lambda d: parse_variable(d, 21), parse_firmware_version):
        try:
            parse(data)
        except ValueError:
            pass


# ---- VESC ----------------------------------------------------------------------------------

@pytest.mark.parametrize("packet, expected", [
    (format_request(0), "02 01 00 00 00 03"),
    (format_request(4), "02 01 04 40 84 03"),
    (format_set_duty(0.5), "02 05 05 00 00 C3 50 3A A5 03"),
    (format_set_duty(-0.25), "02 05 05 FF FF 9E 58 47 8E 03"),
    (format_set_rpm(20000), "02 05 08 00 00 4E 20 08 8C 03"),
    (format_set_rpm(-20000), "02 05 08 FF FF B1 E0 56 FF 03"),
    (format_set_current(2.0), "02 05 06 00 00 07 D0 9F 6F 03"),
    (format_request(30), "02 01 1E F3 FF 03"),
])
def test_vesc_packets_match_the_documented_bytes(packet, expected):
    assert packet == H(expected)


def test_vesc_selective_reply_example_decodes_and_corrupted_packet_is_refused():
    payload, used = parse_packet(H("02 0C 32 00 00 81 80 00 00 75 30 00 F3 00 A2 A0 03"))
    assert used == 17
    mask, erpm, vin, fault = struct.unpack(">IihB", payload[1:])
    assert (erpm, vin / 10, fault) == (30000, 24.3, 0)
    assert parse_packet(H("02 01 04 BF 84 03")) == (None, 1)


def values_payload(erpm: int = 30000, fault: int = 0, tail: bytes = bytes(20)) -> bytes:
    head = struct.pack(">hhiiiihihiiiiiiB", 251, 302, 150, 120, 0, 150, 500, erpm, 243,
                       1, 2, 3, 4, 1000, 1001, fault)
    return bytes([4]) + head + tail


def test_get_values_decodes_scaled_fields_and_short_old_firmware_replies():
    v = parse_values(values_payload(tail=struct.pack(">iB", 2_500_000, 7) + bytes(14) + b"\x01"))
    assert (v.temp_mosfet_c, v.temp_motor_c, v.current_motor_a, v.duty) == (25.1, 30.2, 1.5, 0.5)
    assert (v.erpm, v.input_voltage_v, v.tachometer_abs, v.fault_code) == (30000, 24.3, 1001, 0)
    assert (v.pid_pos, v.controller_id, v.timeout_active) == (2.5, 7, True)
    old = parse_values(values_payload(fault=4, tail=b""))
    assert old.fault == "abs_over_current" and old.timeout_active is None
    with pytest.raises(ValueError):
        parse_values(values_payload()[:40])


def test_framer_resyncs_byte_by_byte():
    good = format_set_duty(0.5)
    stream = H("02 01 04 BF 84 03") + b"\x02\x00\xff" + good + good[:4]
    framer = VescFramer()
    assert framer.feed(stream) == [good[2:7]]
    assert framer.feed(good[4:]) == [good[2:7]]


def test_crc16_check_value():
    assert crc16_xmodem(b"123456789") == 0x31C3  # the catalogue check value of CRC-16/XMODEM


@settings(max_examples=200, deadline=None)
@given(st.binary(min_size=1, max_size=300))
def test_packets_round_trip(payload):
    packet = format_packet(payload)
    assert parse_packet(packet) == (payload, len(packet))
    assert VescFramer().feed(b"\x00\x02" + packet) == [payload]


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=120))
def test_vesc_garbage_never_becomes_a_packet_without_a_valid_crc(data):
    for payload in VescFramer().feed(data):
        assert format_packet(payload) in data
        try:
            parse_values(payload)
        except ValueError:
            pass
