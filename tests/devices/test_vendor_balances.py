"""Balance drivers and emulators against the vendors' manuals and sketches.

Sources:

* A&D: the overload line ``OL,+9999999E+19`` (``OL,-9999999E+19`` below range) of the A&D
  HR-A / HR-AZ instruction manuals' RS-232C data format (and a real HR-100A capture,
  issue 14); a third-party HR-250A reader on GitHub documents the same line.
* HX711: bogde/HX711 0.7.5 (commit be5e3d25) ``examples/HX711_basic_example`` (also
  ``_retry_``/``_timeout_``): ``Serial.begin(57600)``, ``Serial.print("HX711 reading: ");
  Serial.println(scale.read())``, ``delay(1000)``; ``examples/HX711_full_example``:
  ``Serial.begin(38400)``, ``one reading:\\t`` / ``\\t| average:\\t``, ``get_units(10)`` then
  ``delay(5000)`` - about 6.2 s per line; none of them reads the serial port.
* MT-SICS: Mettler Toledo MT-SICS Reference Manual (11780711): level-0 commands I1 (levels
  and versions, five quoted fields), I3 (software version), I5 (software ID), ZI
  ("ZI S": zeroed, weight stable; "ZI D": zeroed, weight dynamic).
"""

from __future__ import annotations

import json
import re

import pytest

from labkit.cli import main
from labkit.devices.balance import and_std, line_regex, mtsics
from labkit.devices.registry import driver_class
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.errors import DeviceError
from labkit.io.clock import VirtualClock, use_clock
from labkit.io.ports import open_port


@pytest.fixture(autouse=True)
def _fresh_plants():
    reset_plants()
    yield
    reset_plants()


def read_lines(port, clock, n: int, timeout: float = 5.0) -> list[bytes]:
    data = b""
    deadline = clock.now() + timeout
    while data.count(b"\n") < n and clock.now() < deadline:
        clock.sleep(0.05)
        data += port.read(4096)
    return data.splitlines(keepends=True)


# ---- A&D ---------------------------------------------------------------------------------

@pytest.mark.parametrize("line", [b"OL,+9999999E+19\r\n", b"OL,-9999999E+19\r\n"])
def test_and_manual_overload_lines_are_overload_never_a_number(line):
    data = and_std.parse_line(line)
    assert isinstance(data, and_std.AndData)
    assert data.overload and data.value is None and not data.stable


def test_and_emulator_sends_the_manual_overload_line_and_probe_reads_it():
    clock = VirtualClock()
    port = open_port("sim://and_std?faults=overload:1&mode=stream", clock=clock, timeout=0,
                     baudrate=2400, bytesize=7, parity="E")
    lines = read_lines(port, clock, 3)
    port.close()
    assert lines[-1] == b"OL,+9999999E+19\r\n"


def test_and_probe_reports_overload_from_the_manual_line(capsys):
    with use_clock(VirtualClock()):
        code = main(["probe", "balance", "--protocol", "and_std", "--port",
                     "sim://and_std?faults=overload:1", "--samples", "1", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    reading = json.loads(out.splitlines()[0])
    assert reading["overload"] is True and reading["value"] is None
    assert reading["raw"].rstrip() == "OL,+9999999E+19"


# ---- HX711 with bogde's example sketches ------------------------------------------------------

def test_bogde_preset_reads_the_basic_example_line_at_57600():
    preset = line_regex.PRESETS["bogde"]
    rx = line_regex.compile_pattern(preset.pattern)
    assert line_regex.parse_value_line(b"HX711 reading: 81234\r\n", rx).value == 81234
    assert line_regex.parse_value_line(b"HX711 reading: -1234\r\n", rx).value == -1234
    assert preset.baudrate == 57600 and preset.unit == "raw"
    cls = driver_class("balance", "line_regex")
    assert cls.serial_defaults({"preset": "bogde"})["baudrate"] == 57600
    assert cls.serial_defaults({"preset": "bogde_full"})["baudrate"] == 38400


def test_bogde_presets_promise_no_tare_and_the_emulated_sketch_ignores_t():
    clock = VirtualClock()
    port = open_port("sim://hx711?preset=bogde&plant=bg&noise_g=0&startup_s=0.1", clock=clock,
                     timeout=0, baudrate=57600)
    cls = driver_class("balance", "line_regex")
    with cls(port, clock, name="hx711 bogde", preset="bogde") as balance:
        shared_plant("bg").set_duty(0.5, clock.now())
        clock.sleep(4.0)
        loaded = balance.read()
        assert loaded.unit == "1" and loaded.value > 81234 + 1000   # raw counts under load
        with pytest.raises(DeviceError, match="cannot tare"):
            balance.zero()
        port.write(b"t")  # what a user would type: the sketch never reads it
        clock.sleep(2.5)
        assert balance.read().value == pytest.approx(loaded.value, abs=5)


def test_bogde_full_example_period_is_covered_by_the_probe_default_wait(capsys):
    with use_clock(VirtualClock()):
        code = main(["probe", "balance", "--protocol", "line_regex", "-o", "preset=bogde_full",
                     "--port", "sim://hx711?preset=bogde_full&startup_s=0.5", "--samples", "3",
                     "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    times = [json.loads(line)["t"] for line in out.splitlines()]
    assert len(times) == 3
    gaps = [b - a for a, b in zip(times, times[1:], strict=False)]
    assert gaps == pytest.approx([6.2, 6.2], abs=0.15)   # longer than the old 3 s default


# ---- MT-SICS --------------------------------------------------------------------------------

@pytest.mark.parametrize("command, pattern", [
    ("I1", r'I1 A "[0-9]+" "[0-9.]+" "[0-9.]*" "[0-9.]*" "[0-9.]*"'),
    ("I3", r'I3 A "[ -~]+"'),
    ("I5", r'I5 A "[ -~]+"'),
])
def test_mtsics_emulator_answers_identification_commands_as_the_manual(command, pattern):
    clock = VirtualClock()
    port = open_port("sim://mtsics", clock=clock, timeout=0, baudrate=9600)
    read_lines(port, clock, 1, timeout=0.5)   # power-on banner
    port.write(mtsics.format_command(command))
    lines = read_lines(port, clock, 1)
    port.close()
    assert re.fullmatch(pattern, lines[-1].rstrip(b"\r\n").decode()), lines
    reply = mtsics.parse_reply(lines[-1])
    assert reply.command == command and reply.status == "A"


@pytest.mark.parametrize("moving, status", [(False, "S"), (True, "D")])
def test_mtsics_zi_says_whether_the_weight_was_stable(moving, status):
    clock = VirtualClock()
    port = open_port("sim://mtsics?plant=zi", clock=clock, timeout=0, baudrate=9600)
    clock.sleep(2.0)
    if moving:
        shared_plant("zi").set_duty(0.5, clock.now())
        clock.sleep(0.2)   # force still rising
    port.read(4096)
    port.write(b"ZI\r\n")
    lines = read_lines(port, clock, 1)
    assert lines[-1] == f"ZI {status}\r\n".encode()
    port.write(b"SI\r\n")
    weight = mtsics.parse_weight(read_lines(port, clock, 1)[-1])
    port.close()
    if not moving:  # zeroed at once (a moving load keeps changing after the zero)
        assert weight.value is not None and abs(weight.value) < 0.05
