"""Each balance driver against its emulator: over sim:// on a virtual clock, and over a
real pseudo-terminal (PtyHost) on the real clock. Expected forces come from the paper's
Fig. 5.25 fit, y[g] = 224e6 * rpm**-1.9, at the plant's steady speed (duty * 2500 rad/s)."""

from __future__ import annotations

import math

import pytest

from labkit.devices.registry import driver_class
from labkit.emulators.balances import AndStdEmulator, MtSicsEmulator
from labkit.emulators.hx711_sketch import Hx711SketchEmulator
from labkit.emulators.plant import shared_plant
from labkit.emulators.rig_plant import RigPlant
from labkit.io.clock import RealClock, VirtualClock
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost

G0 = 9.80665

# name -> (driver protocol, sim URL, serial settings, driver options)
DEVICES = {
    "mtsics": ("mtsics", "sim://mtsics?seed=1&plant=drv", {}, {}),
    "and_std_g": ("and_std", "sim://and_std?seed=1&plant=drv",
                  {"baudrate": 2400, "bytesize": 7, "parity": "E"}, {}),
    "and_std_N": ("and_std", "sim://and_std?seed=1&plant=drv&unit=N",
                  {"baudrate": 2400, "bytesize": 7, "parity": "E"}, {}),
    "hx711_adc": ("line_regex", "sim://hx711?seed=1&plant=drv&startup_s=0.2",
                  {"baudrate": 57600}, {"preset": "hx711_adc"}),
    # bogde's basic example prints raw counts: calibrated here with the emulator's 420 counts/g
    "bogde": ("line_regex", "sim://hx711?seed=1&plant=drv&preset=bogde&startup_s=0.2",
              {"baudrate": 57600}, {"preset": "bogde", "unit": "g", "offset": 81234, "scale": 1 / 420}),
    "bare_float": ("line_regex", "sim://hx711?seed=1&plant=drv&preset=bare_float&startup_s=0.2",
                   {"baudrate": 115200}, {"preset": "bare_float"}),
}


def fig525_grams(duty: float) -> float:
    rpm = duty * 2500.0 * 60.0 / (2.0 * math.pi)
    return 224e6 * rpm**-1.9


def as_grams(reading) -> float:
    return reading.value * 1e3 if reading.quantity == "mass" else reading.value / G0 * 1e3


def open_sim(name: str, clock, **extra_options):
    protocol, url, settings, options = DEVICES[name]
    port = open_port(url, clock=clock, timeout=0, **settings)
    return driver_class("balance", protocol)(port, clock, name=name, **{**options, **extra_options})


@pytest.mark.parametrize("name", sorted(DEVICES))
def test_driver_reads_the_pfr_force_of_fig525(name):
    clock = VirtualClock()
    with open_sim(name, clock) as balance:
        assert balance.identify()["protocol"] == DEVICES[name][0]
        shared_plant("drv").set_duty(0.5, clock.now())
        clock.sleep(4.0)  # 10 motor time constants
        reading = balance.read_stable()
        assert reading.stable and not reading.overload
        expected_unit = "N" if name == "and_std_N" else "kg"
        assert reading.unit == expected_unit
        assert reading.quantity == ("force" if expected_unit == "N" else "mass")
        assert as_grams(reading) == pytest.approx(fig525_grams(0.5), abs=0.03)


@pytest.mark.parametrize("name", sorted(set(DEVICES) - {"bogde"}))  # bogde's sketch cannot tare
def test_motor_ramp_reads_unstable_then_zero_really_moves_the_offset(name):
    clock = VirtualClock()
    # only the HX711 sketches need the host to judge stability; real balances flag it themselves
    extra = {"stable_std": 0.01} if DEVICES[name][0] == "line_regex" else {}
    with open_sim(name, clock, **extra) as balance:
        clock.sleep(1.0)
        shared_plant("drv").set_duty(0.4, clock.now())
        clock.sleep(0.2)
        assert not balance.read().stable  # force changing fast
        clock.sleep(4.0)
        loaded = balance.read_stable()
        assert as_grams(loaded) == pytest.approx(fig525_grams(0.4), abs=0.03)
        balance.zero()
        clock.sleep(0.3)
        assert as_grams(balance.read()) == pytest.approx(0.0, abs=0.02)
        shared_plant("drv").set_duty(0.0, clock.now())
        clock.sleep(4.0)
        unloaded = balance.read_stable()
        assert as_grams(unloaded) == pytest.approx(-fig525_grams(0.4), abs=0.03)


def test_mtsics_tare_reports_the_tare_and_ta_reads_it_back():
    clock = VirtualClock()
    with open_sim("mtsics", clock) as balance:
        shared_plant("drv").set_duty(0.4, clock.now())
        clock.sleep(4.0)
        tare = balance.tare()
        assert tare.raw.startswith(b"T S") and as_grams(tare) == pytest.approx(fig525_grams(0.4), abs=0.03)
        assert balance.tare_value().value == tare.value
        assert as_grams(balance.read()) == pytest.approx(0.0, abs=0.02)
        balance.clear_tare()
        assert balance.tare_value().value == 0.0


def test_and_stream_mode_reads_unsolicited_lines():
    clock = VirtualClock()
    port = open_port("sim://and_std?seed=2&plant=drv&mode=stream", clock=clock, timeout=0,
                     baudrate=2400, bytesize=7, parity="E")
    with driver_class("balance", "and_std")(port, clock, mode="stream") as balance:
        times = [balance.read().t for _ in range(5)]
        gaps = [b - a for a, b in zip(times, times[1:], strict=False)]
        assert gaps == pytest.approx([0.1] * 4, abs=1e-6)  # 10 lines/s, as the balance streams


def test_hx711_raw_counts_with_calibration():
    clock = VirtualClock()
    port = open_port("sim://hx711?seed=2&plant=drv&preset=bare_float&unit=raw&startup_s=0.1&noise_g=0",
                     clock=clock, timeout=0, baudrate=115200)
    options = {"preset": "bare_float", "unit": "g", "offset": 81234, "scale": 1 / 420.0}
    with driver_class("balance", "line_regex")(port, clock, **options) as balance:
        shared_plant("drv").set_duty(0.5, clock.now())
        clock.sleep(4.0)
        assert as_grams(balance.read()) == pytest.approx(fig525_grams(0.5), abs=0.01)


# ---- over a real pseudo-terminal --------------------------------------------------------

PTY_CASES = {
    "mtsics": (MtSicsEmulator, {}, "mtsics", {}, 9600),
    "and_std": (AndStdEmulator, {"unit": "N"}, "and_std", {}, 2400),
    "hx711_adc": (Hx711SketchEmulator, {"startup_s": "0.1", "tare_s": "0.1"}, "line_regex",
                  {"preset": "hx711_adc"}, 57600),
}


@pytest.mark.parametrize("name", sorted(PTY_CASES))
def test_driver_over_a_real_pty(name):
    emulator_cls, emu_options, protocol, options, baud = PTY_CASES[name]
    clock = RealClock()
    plant = RigPlant()
    emulator = emulator_cls(plant=plant, seed=5, options=emu_options)
    with PtyHost(emulator, clock=clock) as host:
        port = open_port(host.path, baudrate=baud, timeout=0)
        with driver_class("balance", protocol)(port, clock, name=name, **options) as balance:
            assert balance.identify()["protocol"] == protocol
            readings = [balance.read(timeout=2.0) for _ in range(3)]
            assert all(math.isfinite(r.value) and not r.overload for r in readings)
            assert all(abs(as_grams(r)) < 0.05 for r in readings)  # motor at rest: no force
            balance.zero(timeout=5.0)
