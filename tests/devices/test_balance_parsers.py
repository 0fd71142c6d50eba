"""Balance parsers: the byte examples of PROTOCOLS 1.1/1.2/1.4, and hypothesis fuzzing
(no crash, garbage never becomes a reading, valid frames round-trip format -> parse)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.devices.balance import and_std, line_regex, mtsics
from labkit.devices.link import FrameError, describe_serial
from labkit.units import UnitError, to_si

FUZZ = settings(max_examples=300, deadline=None)

# ---- known frames (PROTOCOLS 1.1 byte-level examples) ----------------------------------


def test_mtsics_manual_examples():
    stable = mtsics.parse_weight(bytes.fromhex("53205320202020202031322E33342067" "0D0A"))
    assert (stable.status, stable.value, stable.unit, stable.stable) == ("S", 12.34, "g", True)
    dynamic = mtsics.parse_weight(bytes.fromhex("53204420202020202D302E30322067" "0D0A"))
    assert (dynamic.value, dynamic.stable) == (-0.02, False)
    over = mtsics.parse_weight(b"S +\r\n")
    assert over.overload and over.value is None
    under = mtsics.parse_weight(b"S -\r\n")
    assert under.overload and under.value is None
    assert mtsics.parse_reply(b"Z A\r\n") == mtsics.MtReply("Z", "A")
    assert mtsics.parse_reply(b"ES\r\n").is_general_error
    serial_no = mtsics.parse_reply(b'I4 A "B207696838"\r\n')
    assert mtsics.parse_quoted_info(serial_no) == "B207696838"
    assert mtsics.format_command("SI") == bytes.fromhex("53490D0A")


def test_mtsics_i2_type_with_spaces_is_parsed_from_the_right():
    reply = mtsics.parse_reply(b'I2 A "XS205 DualRange 220.00 g"')
    info = mtsics.parse_i2(mtsics.parse_quoted_info(reply))
    assert info == {"model": "XS205 DualRange", "capacity": 220.0, "capacity_unit": "g"}


@pytest.mark.parametrize("line", [
    b"S S", b"S S 12.34", b"S S abc g", b"S S 1.2.3 g", b"S X 1.0 g", b"S + 999.9 g",
    b"s s 1.0 g", b"\xffS S 1.0 g", b"S S nan g", b"S S inf g", b"S S 1e999 g", b"",
])
def test_mtsics_malformed_weights_are_rejected(line):
    with pytest.raises(FrameError):
        mtsics.parse_weight(line)


def test_and_manual_examples():
    st_line = and_std.parse_line(bytes.fromhex("53542C2B30303031322E3334202067" "0D0A"))
    assert st_line == and_std.AndData("ST", 12.34, "g")
    us_line = and_std.parse_line(b"US,-00000.02  g\r\n")
    assert (us_line.value, us_line.stable) == (-0.02, False)
    newton = and_std.parse_line(b"ST,+00012.34  N\r\n")
    assert newton.unit == "N"
    for filler in (b"OL,+999999.9  g\r\n", b"OL,-99999999 PC\r\n"):
        ol = and_std.parse_line(filler)
        assert ol.overload and ol.value is None  # the digits are a filler, never a reading
    assert and_std.parse_line(b"EC,E11\r\n") == and_std.AndError("E11")
    assert "stability" in and_std.AndError("E11").meaning
    assert and_std.parse_line(b"\x06") == and_std.AndAck()
    assert and_std.parse_line(b"ST,OK,+00012.34  g").comparator == "OK"
    assert len(and_std.format_data("ST", 12.34, "g")) == 17


@pytest.mark.parametrize("line", [
    b"ST,+0012.34  g", b"ST,+00012.34 g", b"ST,+000.2.34  g", b"XX,+00012.34  g",
    b"ST,+........  g", b"ST,+00012.34   ", b"EC,E1", b"ST,00012.345  g",
])
def test_and_malformed_lines_are_rejected(line):
    with pytest.raises(FrameError):
        and_std.parse_line(line)


def test_line_regex_presets_read_their_sketch_lines():
    examples = {
        "hx711_adc": (b"Load_cell output val: 12.34\r\n", 12.34),
        "bogde": (b"HX711 reading: 81234\r\n", 81234),
        "bogde_full": (b"one reading:\t1.23\t| average:\t1.25\r\n", 1.25),
        "bare_float": (b"  -0.5\r\n", -0.5),
    }
    for preset, (line, value) in examples.items():
        rx = line_regex.compile_pattern(line_regex.PRESETS[preset].pattern)
        assert line_regex.parse_value_line(line, rx).value == value
    rx = line_regex.compile_pattern(line_regex.PRESETS["bogde"].pattern)
    with pytest.raises(FrameError):
        line_regex.parse_value_line(b"HX711 not found.", rx)
    rx = line_regex.compile_pattern(line_regex.PRESETS["hx711_adc"].pattern)
    for banner in (b"Starting...", b"Startup is complete", b"Tare complete", b"Load_cell output val: nan"):
        with pytest.raises(FrameError):
            line_regex.parse_value_line(banner, rx)


def test_pattern_without_value_group_is_refused():
    with pytest.raises(ValueError, match="value"):
        line_regex.compile_pattern(r"w=(\d+)")


def test_units_to_si():
    assert to_si(12.34, "g") == ("mass", pytest.approx(0.01234), "kg")
    assert to_si(0.5, "N") == ("force", 0.5, "N")
    assert to_si(1.0, "lb")[1] == pytest.approx(0.45359237)
    with pytest.raises(UnitError, match="PC"):
        to_si(3, "PC")
    assert describe_serial({"baudrate": 2400, "bytesize": 7, "parity": "E", "stopbits": 1}) == "2400 7E1"


# ---- fuzzing ----------------------------------------------------------------------------

junk = st.binary(max_size=40)
printable = st.text(alphabet=st.characters(min_codepoint=0x20, max_codepoint=0x7E), max_size=30)


@FUZZ
@given(junk)
def test_fuzz_mtsics_never_crashes_and_values_are_finite(data):
    try:
        weight = mtsics.parse_weight(data)
    except FrameError:
        return
    assert weight.status in "SD+-IL"
    if weight.value is not None:
        assert math.isfinite(weight.value) and weight.status in "SD"
    else:
        assert weight.status in "+-IL"


@FUZZ
@given(printable)
def test_fuzz_mtsics_printable_text_gives_a_reading_only_for_weight_shapes(text):
    try:
        weight = mtsics.parse_weight(text.encode())
    except FrameError:
        return
    if weight.value is not None:
        tokens = text.split()
        assert tokens[1] in "SDA" and float(tokens[2]) == weight.value


@FUZZ
@given(st.sampled_from("SD"), st.floats(-99999, 99999, allow_nan=False), st.integers(0, 4),
       st.sampled_from(["g", "kg", "mg", "N", "ct"]))
def test_fuzz_mtsics_round_trip(status, value, decimals, unit):
    frame = mtsics.format_weight("S", status, value, unit, decimals)
    weight = mtsics.parse_weight(frame)
    assert weight.value == float(f"{value:.{decimals}f}")
    assert (weight.status, weight.unit) == (status, unit)


@FUZZ
@given(st.one_of(junk, printable.map(str.encode)))
def test_fuzz_and_never_crashes_and_overload_has_no_value(data):
    try:
        parsed = and_std.parse_line(data)
    except FrameError:
        return
    if isinstance(parsed, and_std.AndData):
        if parsed.overload:
            assert parsed.value is None
        else:
            assert parsed.value is not None and math.isfinite(parsed.value)


@FUZZ
@given(st.sampled_from(["ST", "US"]), st.floats(-99999, 99999, allow_nan=False),
       st.sampled_from([(2, "g"), (4, "N"), (3, "kg"), (0, "PC")]))
def test_fuzz_and_round_trip(header, value, decimals_unit):
    decimals, unit = decimals_unit
    try:
        frame = and_std.format_data(header, value, unit, decimals)
    except ValueError:
        return  # does not fit the 8-character field
    assert len(frame) == 17
    parsed = and_std.parse_line(frame)
    assert parsed.value == pytest.approx(float(f"{value:.{decimals}f}"), abs=0)
    assert (parsed.header, parsed.unit) == (header, unit)


@FUZZ
@given(st.sampled_from(sorted(line_regex.PRESETS)), st.one_of(junk, printable.map(str.encode)))
def test_fuzz_line_regex_never_crashes(preset, data):
    rx = line_regex.compile_pattern(line_regex.PRESETS[preset].pattern)
    try:
        parsed = line_regex.parse_value_line(data, rx)
    except FrameError:
        return
    assert math.isfinite(parsed.value)


@FUZZ
@given(st.sampled_from(sorted(line_regex.PRESETS)), st.floats(-1e6, 1e6, allow_nan=False),
       st.integers(0, 4))
def test_fuzz_line_regex_round_trip(preset, value, decimals):
    rx = line_regex.compile_pattern(line_regex.PRESETS[preset].pattern)
    line = line_regex.format_value_line(preset, value, decimals)
    # bogde's basic example prints scale.read(): whole ADC counts
    expected = float(round(value)) if preset == "bogde" else float(f"{value:.{decimals}f}")
    assert line_regex.parse_value_line(line, rx).value == expected


@FUZZ
@given(st.binary(max_size=30))
def test_fuzz_garbage_around_a_valid_frame_is_not_read(junk_bytes):
    """Junk glued to a frame makes it invalid or leaves it unchanged, never another number."""
    frame = b"S S      12.34 g"
    for data in (junk_bytes + frame, frame + junk_bytes):
        try:
            weight = mtsics.parse_weight(data)
        except FrameError:
            continue
        assert weight.value == 12.34
