"""Tachometer parsers: the documented frames decode, garbage never becomes a reading."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.devices.tachometer.labkit_tach import (
    consistent_with_ppr,
    format_command,
    parse_banner,
    parse_tach_sample,
)
from labkit.devices.tachometer.lutron16 import Lutron16Framer, parse_lutron16

# PROTOCOLS 2.1 example: STX '4' '1' annunciator '0' '1' '00012345' CR -> +1234.5
DOC_FRAME = bytes([0x02, 0x34, 0x31, 0x30, 0x30, 0x30, 0x31]) + b"00012345" + b"\x0d"


def lutron_frame(value_digits: bytes, point: int = 0, negative: bool = False,
                 display: bytes = b"1", code: bytes = b"00") -> bytes:
    sign = b"1" if negative else b"0"
    return b"\x024" + display + code + sign + str(point).encode() + value_digits + b"\r"


def test_lutron_doc_example_decodes_to_1234_5():
    frame = parse_lutron16(DOC_FRAME)
    assert frame.value == pytest.approx(1234.5)
    assert frame.display == "1" and frame.annunciator == "00" and not frame.over_range


@pytest.mark.parametrize("digits, point, negative, expected", [
    (b"00001234", 0, False, 1234.0),
    (b"00001234", 3, False, 1.234),
    (b"00099999", 0, False, 99999.0),
    (b"00000050", 1, True, -5.0),
    (b"00000000", 0, False, 0.0),
])
def test_lutron_sign_and_decimal_point(digits, point, negative, expected):
    assert parse_lutron16(lutron_frame(digits, point, negative)).value == pytest.approx(expected)


def test_lutron_over_range_has_no_value():
    frame = parse_lutron16(lutron_frame(b"  OL    "))
    assert frame.over_range and frame.value is None


@pytest.mark.parametrize("bad", [
    DOC_FRAME[:-1] + b"\n",                  # wrong end byte
    b"\x035" + DOC_FRAME[2:],                 # wrong start
    DOC_FRAME[:5] + b"2" + DOC_FRAME[6:],     # polarity '2'
    DOC_FRAME[:6] + b"7" + DOC_FRAME[7:],     # decimal point 7
    DOC_FRAME[:9] + b"1x" + DOC_FRAME[11:],   # letter among the digits
    DOC_FRAME[:15],                           # short
])
def test_lutron_malformed_frames_raise(bad):
    with pytest.raises(ValueError):
        parse_lutron16(bad)


def test_framer_resyncs_after_junk_and_a_frame_started_mid_way():
    stream = DOC_FRAME[7:] + b"\x00\xff\x02junk" + DOC_FRAME + lutron_frame(b"00000042")
    framer = Lutron16Framer()
    frames = []
    for i in range(0, len(stream), 3):  # arrive in 3-byte reads
        frames += framer.feed(stream[i:i + 3])
    assert [parse_lutron16(f).value for f in frames] == [pytest.approx(1234.5), 42.0]


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=200))
def test_lutron_framer_and_parser_never_crash_and_only_accept_well_formed_frames(data):
    for frame in Lutron16Framer().feed(data):
        try:
            decoded = parse_lutron16(frame)
        except ValueError:
            continue
        assert frame[0] == 0x02 and frame[-1] == 0x0D and len(frame) == 16
        if decoded.value is not None:
            assert frame[7:15].isdigit()


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 99_999_999), st.integers(0, 3), st.booleans(), st.binary(max_size=20))
def test_lutron_frames_survive_surrounding_garbage(number, point, negative, junk):
    frame = lutron_frame(b"%08d" % number, point, negative)
    framer = Lutron16Framer()
    got = framer.feed(junk.replace(b"\x02", b"") + frame)
    assert len(got) == 1
    value = parse_lutron16(got[0]).value
    assert value == pytest.approx((-1 if negative else 1) * number / 10**point)


# ---- labkit pulse tachometer ---------------------------------------------------------------

def test_sample_line_fields():
    s = parse_tach_sample(b"T,12,3456,24000.0,2500.0,40,0")
    assert (s.seq, s.t_ms, s.rpm, s.period_us, s.pulses) == (12, 3456, 24000.0, 2500.0, 40)
    assert s.flags == frozenset()


def test_flags_decode():
    assert parse_tach_sample(b"T,1,2,0.0,0.0,0,Z").flags == {"zero_speed"}
    assert parse_tach_sample(b"T,1,2,1.0,60000000.0,1,ON").flags == {"over_range", "noisy"}


@pytest.mark.parametrize("bad", [
    b"T,1,2,3,4,5", b"X,1,2,3,4,5,0", b"T,-1,2,3.0,4.0,5,0", b"T,1,2,abc,4.0,5,0",
    b"T,1,2,3.0,4.0,5,Q", b"T,1,2,5.0,0.0,0,Z", b"T,1,2,100.0,0,3,0", b"T,1,2,1..0,4,5,0",
    b"24000 RPM", b"detect", b"SLOW!", b"",
])
def test_bad_lines_raise(bad):
    with pytest.raises(ValueError):
        parse_tach_sample(bad)


def test_100k_rpm_at_one_pulse_per_rev_is_consistent():
    # 100 000 RPM, 1 PPR: 600 us period (PROTOCOLS 2.3)
    sample = parse_tach_sample(b"T,1,2,100000.0,600.0,166,0")
    assert consistent_with_ppr(sample, 1)
    assert not consistent_with_ppr(sample, 2)


def test_banner_and_commands():
    assert parse_banner(b"# labkit-tach 1.0 ppr=2 rate=10 zto=1000") == {
        "version": "1.0", "ppr": "2", "rate": "10", "zto": "1000"}
    assert parse_banner(b"# just a comment") is None
    assert format_command("PPR", 2) == b"PPR 2\n"
    assert format_command("ID?") == b"ID?\n"
    with pytest.raises(ValueError):
        format_command("PPR", 0)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=80))
def test_tach_parser_never_crashes_on_bytes(line):
    try:
        sample = parse_tach_sample(line)
    except ValueError:
        return
    assert line.strip().startswith(b"T,") and sample.rpm >= 0


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**31), st.integers(0, 2**31), st.floats(50, 1e7), st.integers(1, 10_000))
def test_tach_lines_round_trip(seq, t_ms, period_us, pulses):
    rpm = 60e6 / period_us
    line = f"T,{seq},{t_ms},{rpm:.1f},{period_us:.1f},{pulses},0".encode()
    sample = parse_tach_sample(line)
    assert (sample.seq, sample.t_ms, sample.pulses) == (seq, t_ms, pulses)
    assert consistent_with_ppr(sample, 1)


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=30).filter(lambda b: b"\n" not in b and b"T," not in b and b"#" not in b
                                     and b"OK" not in b and b"ERR" not in b and b"ID " not in b))
def test_junk_before_a_line_is_dropped(junk):
    from labkit.devices.tachometer.labkit_tach import strip_junk

    line = b"T,5,500,24000.0,2500.0,40,0"
    assert parse_tach_sample(strip_junk(junk + line)).rpm == 24000.0


# ---- Monarch "@" protocol -------------------------------------------------------------------

@pytest.mark.parametrize("line, rpm", [(b"1234.5", 1234.5), (b" 60000 RPM", 60000.0), (b"0", 0.0),
                                       (b"+12.25rpm", 12.25)])
def test_monarch_value_lines(line, rpm):
    from labkit.devices.tachometer.monarch import parse_display_value

    assert parse_display_value(line) == rpm


@pytest.mark.parametrize("bad", [b"OK", b"ERR", b"ACT-3X", b"12.3.4", b"1e5", b"", b"12 Hz", b"--1"])
def test_monarch_non_values_raise(bad):
    from labkit.devices.tachometer.monarch import parse_display_value

    with pytest.raises(ValueError):
        parse_display_value(bad)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=60))
def test_monarch_framer_and_parser_never_crash(data):
    from labkit.devices.tachometer.monarch import EolFramer, parse_display_value

    for line in EolFramer().feed(data):
        try:
            value = parse_display_value(line)
        except ValueError:
            continue
        assert line.strip(b" +-.0123456789RPMrpm") == b""   # only a number (and its unit) was read
        assert value == value   # not NaN
