"""HX711 line driver (line_regex) fault matrix, the cases the sensor matrix lacked: overload
(the ADC at its rails) and reset (the sketch reboots mid-session, prints its banner again and
re-tares), plus a sketch that stops printing. Every preset's emulated sketch over ``sim://``
on a virtual clock, and a reset over a real pseudo-terminal.

Known answers: the emulated bridge prints ``grams * calibration + 81234`` counts, clipped to
the HX711's 24-bit rails 0x7FFFFF / -0x800000 (datasheet). With ``calibration=4e6`` counts/g
the positive rail is (8388607 - 81234) / 4e6 = 2.0768 g, below the ~4.02 g of PFR force at
duty 0.5 (Fig. 5.25 fit at 11 937 RPM), so that load overloads the cell.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.devices.balance import line_regex
from labkit.devices.link import FrameError
from labkit.devices.registry import driver_class
from labkit.emulators.hx711_sketch import Hx711SketchEmulator
from labkit.emulators.plant import shared_plant
from labkit.emulators.rig_plant import RigPlant
from labkit.errors import DeviceTimeout
from labkit.io.clock import RealClock, VirtualClock
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost

PRESETS = ("hx711_adc", "bogde_full", "bare_float")
BAUD = {"hx711_adc": 57600, "bogde_full": 38400, "bare_float": 115200}
#: bogde's full example prints every 6.2 s; these tests are about rails and banners, so its
#: emulated sketch prints at the ADC's 10 SPS here
FAST = {"bogde_full": "&rate_hz=10"}
RAIL_G = (0x7FFFFF - 81234) / 4e6           # 2.0768 g: the positive rail at 4e6 counts/g
FORCE_G = 224e6 * (0.5 * 2500.0 * 60.0 / (2.0 * math.pi)) ** -1.9  # Fig. 5.25 at duty 0.5


def open_hx711(preset: str, query: str = "", clock=None, **options):
    clock = clock or VirtualClock()
    port = open_port(f"sim://hx711?seed=3&plant=hx&preset={preset}&startup_s=0.3&noise_g=0"
                     f"{FAST.get(preset, '')}{query}",
                     clock=clock, timeout=0, baudrate=BAUD[preset])
    cls = driver_class("balance", "line_regex")
    extra = {"tare_settle_s": 0.8} if preset != "hx711_adc" else {}
    return cls(port, clock, name=f"hx711 {preset}", preset=preset, **{**extra, **options}), clock


def grams(reading) -> float:
    return reading.value * 1e3


def assert_overload(reading) -> None:
    assert reading.overload and not reading.stable and math.isnan(reading.value)
    assert "overload" in reading.flags


# ---- overload ----------------------------------------------------------------------------

@pytest.mark.parametrize("preset", PRESETS)
def test_load_beyond_the_adc_rail_prints_the_rail_code_and_reads_as_overload(preset):
    balance, clock = open_hx711(preset, "&unit=raw&calibration=4e6", unit="raw")
    clock.sleep(1.0)
    assert not balance.read().overload                  # no load: in range
    shared_plant("hx").set_duty(0.5, clock.now())
    clock.sleep(4.0)
    reading = balance.read()
    assert_overload(reading)
    assert b"8388607" in reading.raw                    # the sketch printed the rail code


@pytest.mark.parametrize("preset", PRESETS)
def test_cell_wired_the_other_way_round_saturates_at_the_negative_rail(preset):
    # swapped signal wires: counts fall with load (calibration -4e6 counts/g)
    balance, clock = open_hx711(preset, "&unit=raw&calibration=-4e6", unit="raw")
    shared_plant("hx").set_duty(0.8, clock.now())       # 1.65 g: -6.5e6 counts, in range
    clock.sleep(4.0)
    assert not balance.read().overload
    shared_plant("hx").set_duty(0.5, clock.now())       # 4.02 g: beyond -0x800000
    clock.sleep(4.0)
    reading = balance.read()
    assert_overload(reading)
    assert b"-8388608" in reading.raw


@pytest.mark.parametrize("preset", PRESETS)
def test_calibrated_sketch_at_the_rail_is_overload_beyond_capacity(preset):
    # a calibrated sketch prints the railed code converted to grams: a constant 2.08 g
    balance, clock = open_hx711(preset, "&calibration=4e6", capacity=2.0)
    shared_plant("hx").set_duty(0.5, clock.now())
    clock.sleep(4.0)
    reading = balance.read()
    assert_overload(reading)
    assert f"{RAIL_G:.2f}".encode() in reading.raw
    # the same cell below its capacity reads the force as a number
    shared_plant("hx").set_duty(0.8, clock.now())       # 19 099 RPM: 1.65 g
    clock.sleep(4.0)
    below = balance.read()
    assert not below.overload and grams(below) == pytest.approx(1.65, abs=0.02)


@pytest.mark.parametrize("preset", PRESETS)
def test_overload_fault_in_the_stream_is_never_a_number(preset):
    balance, clock = open_hx711(preset, "&unit=raw&faults=overload:0.5", unit="raw",
                                offset=81234, scale=1 / 420.0)
    balance.start_continuous()
    clock.sleep(5.0)
    readings = balance.readings_since(1.0)
    over = [r for r in readings if r.overload]
    assert len(readings) >= 30 and 5 <= len(over) < len(readings)
    assert all(math.isnan(r.value) and not r.stable for r in over)
    assert all(abs(r.value) < 1e-3 for r in readings if not r.overload)  # 0 g, no load


# ---- reset: banner again, tare lost --------------------------------------------------------

@pytest.mark.parametrize("continuous", [False, True], ids=["read", "continuous"])
@pytest.mark.parametrize("preset", PRESETS)
def test_reboot_mid_session_is_flagged_once_and_the_banner_is_never_a_weight(preset, continuous):
    balance, clock = open_hx711(preset, "&faults=reset_at:6")
    shared_plant("hx").set_duty(0.5, clock.now())
    if continuous:
        balance.start_continuous()
    clock.sleep(4.0)
    before = balance.read()
    assert grams(before) == pytest.approx(FORCE_G, abs=0.02)
    assert balance.resets_seen == 0                     # the banner at open is no reset
    readings = [balance.read(timeout=3.0) for _ in range(40)]   # through the reboot at 6 s
    flagged = [r for r in readings if "device_reset" in r.flags]
    assert balance.resets_seen == 1 and len(flagged) == 1
    assert flagged[0].flags >= {"device_reset", "tare_lost"} and flagged[0].t > 6.0
    # the sketch tared itself at boot with the force on the cell: 0 g from then on
    for r in readings:
        expected = 0.0 if r.t >= flagged[0].t else FORCE_G
        assert grams(r) == pytest.approx(expected, abs=0.02), r.raw
    assert "device_reset" not in balance.read().flags   # flagged once, not forever


def test_open_during_boot_and_tare_confirmation_are_not_resets():
    balance, clock = open_hx711("hx711_adc")            # opened as the sketch boots
    balance.read(timeout=2.0)
    balance.zero(timeout=5.0)                           # "Tare complete" is no banner
    balance.read()
    assert balance.resets_seen == 0


def test_boot_pattern_option_overrides_and_disables():
    balance, clock = open_hx711("bare_float", "&faults=reset_at:3", boot_pattern="")
    clock.sleep(2.0)
    readings = [balance.read(timeout=3.0) for _ in range(20)]
    assert balance.resets_seen == 0 and not any("device_reset" in r.flags for r in readings)
    with pytest.raises(ValueError, match="boot_pattern"):
        open_hx711("bare_float", boot_pattern="(")


def test_reboot_over_a_real_pty_is_flagged():
    clock = RealClock()
    plant = RigPlant()
    emulator = Hx711SketchEmulator(plant=plant, seed=5, faults={"reset_at": 0.8},
                                   options={"startup_s": "0.1", "rate_hz": "40"})
    with PtyHost(emulator, clock=clock) as host:
        port = open_port(host.path, baudrate=57600, timeout=0)
        with driver_class("balance", "line_regex")(port, clock, name="pty-hx711") as balance:
            readings = [balance.read(timeout=2.0) for _ in range(50)]   # ~1.25 s at 40 SPS
            assert balance.resets_seen == 1
    assert sum("device_reset" in r.flags for r in readings) == 1
    assert all(math.isfinite(r.value) and abs(grams(r)) < 0.05 for r in readings)


# ---- the sketch stops printing ---------------------------------------------------------------

def test_silent_sketch_times_out_naming_device_and_last_bytes():
    balance, clock = open_hx711("hx711_adc", "&faults=stop_at:2")
    clock.sleep(1.5)
    last = balance.read()
    clock.sleep(1.0)
    start = clock.now()
    with pytest.raises(DeviceTimeout, match="no reply in 1.5 s") as err:
        balance.read(timeout=1.5)
    assert clock.now() - start == pytest.approx(1.5, abs=0.05)
    assert err.value.device == "hx711 hx711_adc"
    assert err.value.last_bytes.endswith(b"Load_cell output val: 0.00\r\n")
    assert last.raw.startswith(b"Load_cell output val:")


# ---- parser properties (hypothesis) ----------------------------------------------------------

FUZZ = settings(max_examples=300, deadline=None)
BANNERS = {
    "hx711_adc": [b"Starting...", b"Startup is complete", b"\x00\xff\xfeStarting...",
                  b"Timeout, check MCU>HX711 wiring and pin designations"],
    "bogde_full": [b"HX711 Demo", b"Initializing the scale", b"Before setting up the scale:",
              b"After setting up the scale:"],
    "bare_float": [b"HX711 scale ready", b"Load cell ready"],
}


@pytest.mark.parametrize("preset", PRESETS)
def test_known_banner_lines_are_boot_lines_and_no_values(preset):
    pattern = line_regex.compile_pattern(line_regex.PRESETS[preset].pattern)
    boot = line_regex.compile_boot_pattern(line_regex.PRESETS[preset].boot_pattern)
    for line in BANNERS[preset]:
        assert line_regex.is_boot_line(line, boot)
        with pytest.raises(FrameError):
            line_regex.parse_value_line(line, pattern)
    # Arduino's own non-numbers are garbage, not a reboot
    for line in (b"nan", b"inf", b"ovf", b" -nan"):
        assert not (preset == "bare_float" and line_regex.is_boot_line(line, boot))


@FUZZ
@given(st.sampled_from(PRESETS), st.one_of(st.binary(max_size=40), st.text(max_size=40).map(str.encode)))
def test_fuzz_no_line_is_both_a_value_and_a_boot_line(preset, data):
    pattern = line_regex.compile_pattern(line_regex.PRESETS[preset].pattern)
    boot = line_regex.compile_boot_pattern(line_regex.PRESETS[preset].boot_pattern)
    is_boot = line_regex.is_boot_line(data, boot)       # never raises on any bytes
    try:
        line_regex.parse_value_line(data, pattern)
    except FrameError:
        return
    assert not is_boot


@FUZZ
@given(st.sampled_from(PRESETS), st.floats(-1e7, 1e7, allow_nan=False), st.integers(0, 4))
def test_fuzz_value_lines_are_never_boot_lines(preset, value, decimals):
    boot = line_regex.compile_boot_pattern(line_regex.PRESETS[preset].boot_pattern)
    assert not line_regex.is_boot_line(line_regex.format_value_line(preset, value, decimals), boot)
