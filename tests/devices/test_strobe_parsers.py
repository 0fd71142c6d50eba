"""The labkit strobe's status line, banner and commands (docs/reference/devices-strobe.md): documented
lines decode, any well-formed line round-trips, garbage never becomes a status."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.devices.strobe.protocol import (
    FLAG_NAMES,
    STROBE_FLAGS,
    format_command,
    parse_banner,
    parse_status_line,
    strip_junk,
    width_for_blur,
)


def test_the_documented_line_decodes():
    status = parse_status_line(b"S,12,13001,1000.0000,999.5000,123.4,0", t=2.5, divider=1)
    assert (status.seq, status.t_ms, status.rotor_hz, status.strobe_hz, status.phase_deg) == \
        (12, 13001, 1000.0, 999.5, 123.4)
    assert status.apparent_hz == pytest.approx(0.5) and status.locked and status.t == 2.5
    assert status.as_json()["value"] == 999.5 and status.as_json()["unit"] == "Hz"


def test_flags_decode_and_say_whether_the_window_is_trustworthy():
    status = parse_status_line(b"S,1,200,0.0000,0.0000,0.0,ZL")
    assert status.flags == {"no_pulses", "unlocked"} and not status.locked
    assert status.apparent_hz is None
    off = parse_status_line(b"S,1,200,500.0000,0.0000,10.0,X")
    assert off.flags == {"lamp_off"} and not off.locked           # no flashes, nothing to trust
    cut = parse_status_line(b"S,1,200,500.0000,499.0000,10.0,W")
    assert cut.locked                                              # a shorter flash is still right
    assert set(FLAG_NAMES.values()) == set(STROBE_FLAGS)


def test_the_divider_enters_the_apparent_frequency():
    status = parse_status_line(b"S,1,200,900.0000,299.5000,10.0,0", divider=3)
    assert status.apparent_hz == pytest.approx(1.5)


@pytest.mark.parametrize("line, field", [
    (b"S,1,200,500.000,499.0000,10.0,0", "f_rot_hz"),        # 3 decimals
    (b"S,1,200,500.0000,-1.0000,10.0,0", "f_strobe_hz"),     # negative
    (b"S,1,200,500.0000,499.0000,360.0,0", "phase_deg"),     # not below 360
    (b"S,1,200,500.0000,499.0000,10.0,ZZ", "flags"),         # repeated letter
    (b"S,1,200,500.0000,499.0000,10.0,Q", "flags"),          # unknown letter
    (b"S,x,200,500.0000,499.0000,10.0,0", "seq"),
    (b"T,1,200,500.0,2000.0,5,0", "S line"),                 # a tachometer line
    (b"S,1,200,500.0000,499.0000,10.0", "S line"),            # a field short
])
def test_a_bad_field_is_named(line, field):
    with pytest.raises(ValueError, match=field):
        parse_status_line(line)


def firmware_line(seq, t_ms, rot_e4, strobe_e4, tenths, flags) -> bytes:
    """A status line printed the way the sketch prints it (integer arithmetic)."""
    rot = f"{rot_e4 // 10000}.{rot_e4 % 10000:04d}"
    strobe = f"{strobe_e4 // 10000}.{strobe_e4 % 10000:04d}"
    text = f"S,{seq},{t_ms},{rot},{strobe},{tenths // 10}.{tenths % 10},{flags or '0'}"
    return text.encode()


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 2**32 - 1), st.integers(0, 4000_0000),
       st.integers(0, 4000_0000), st.integers(0, 3599),
       st.lists(st.sampled_from(sorted(FLAG_NAMES)), unique=True, max_size=len(FLAG_NAMES)))
def test_every_line_the_sketch_can_print_round_trips(seq, t_ms, rot_e4, strobe_e4, tenths, letters):
    flags = "".join(letters)
    status = parse_status_line(firmware_line(seq, t_ms, rot_e4, strobe_e4, tenths, flags))
    assert status.seq == seq and status.t_ms == t_ms
    assert status.rotor_hz == pytest.approx(rot_e4 / 1e4, abs=1e-9)
    assert status.strobe_hz == pytest.approx(strobe_e4 / 1e4, abs=1e-9)
    assert status.phase_deg == pytest.approx(tenths / 10, abs=1e-9)
    assert status.flags == frozenset(FLAG_NAMES[c] for c in flags)


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=80))
def test_garbage_is_rejected_with_a_value_error_or_parses_to_a_sane_status(data):
    try:
        status = parse_status_line(data)
    except ValueError:
        return
    assert status.rotor_hz >= 0 and status.strobe_hz >= 0 and 0 <= status.phase_deg < 360
    assert status.flags <= set(STROBE_FLAGS)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=12), st.binary(max_size=12))
def test_junk_around_a_line_is_cut_off_or_the_line_is_rejected(before, after):
    line = b"S,3,400,250.0000,249.5000,90.0,0"
    junk = before.replace(b"S,", b"").replace(b"OK", b"").replace(b"ERR", b"").replace(b"ID ", b"") \
        .replace(b"#", b"")
    cleaned = strip_junk(junk + line + after)
    try:
        status = parse_status_line(cleaned)
    except ValueError:
        return                                   # trailing junk spoils the line: rejected
    assert status.rotor_hz == 250.0 and status.strobe_hz == 249.5   # never a wrong number


def test_banner_and_commands():
    assert parse_banner(b"# labkit-strobe 1.0 offset=0.500 width=10 div=1 rate=1") == {
        "version": "1.0", "offset": "0.500", "width": "10", "div": "1", "rate": "1"}
    assert parse_banner(b"# labkit-tach 1.0 ppr=1") is None
    assert format_command("OFFSET", 0.5) == b"OFFSET 0.5\n"
    assert format_command("OFFSET", -1.25) == b"OFFSET -1.25\n"
    assert format_command("WIDTH", 20) == b"WIDTH 20\n"
    assert format_command("DIV", 3) == b"DIV 3\n"
    assert format_command("OFF") == b"OFF\n" and format_command("ID?") == b"ID?\n"
    for bad in (("OFFSET", 101.0), ("WIDTH", 0), ("WIDTH", 2.5), ("DIV", 101), ("RATE", 0),
                ("OFFSET", float("nan")), ("FOO", 1)):
        with pytest.raises(ValueError):
            format_command(*bad)


def test_width_for_a_given_angular_blur():
    # 1 degree at 2 kHz: 1/(360*2000) s = 1.39 us; at 100 Hz 27.8 us (docs/reference/devices-strobe.md)
    assert width_for_blur(2000.0, 1.0) == pytest.approx(1.389, abs=1e-3)
    assert width_for_blur(100.0, 1.0) == pytest.approx(27.78, abs=1e-2)
