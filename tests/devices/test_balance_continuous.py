"""Continuous output (MT-SICS SIR, A&D SIR / stream mode, HX711 sketches) read by one
reader per balance into a timestamped buffer; commands pause the stream around them."""

from __future__ import annotations

import math

import pytest

from labkit.devices.registry import driver_class
from labkit.emulators.balances import MtSicsEmulator
from labkit.emulators.plant import shared_plant
from labkit.emulators.rig_plant import RigPlant
from labkit.errors import DeviceDisconnected
from labkit.io.clock import RealClock, VirtualClock
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost

CASES = {
    # name -> (protocol, url, settings, options, update rate of the device in Hz)
    "mtsics": ("mtsics", "sim://mtsics?seed=1&plant=cont", {}, {}, 20.0),
    "and_sir": ("and_std", "sim://and_std?seed=1&plant=cont",
                {"baudrate": 2400, "bytesize": 7, "parity": "E"}, {}, 10.0),
    "and_stream_mode": ("and_std", "sim://and_std?seed=1&plant=cont&mode=stream",
                        {"baudrate": 2400, "bytesize": 7, "parity": "E"}, {"mode": "stream"}, 10.0),
    "hx711": ("line_regex", "sim://hx711?seed=1&plant=cont&startup_s=0.1", {"baudrate": 57600},
              {"preset": "hx711_adc", "tare_reply": "Tare complete"}, 10.0),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_continuous_readings_arrive_at_the_device_rate_and_survive_a_zero(name):
    protocol, url, settings, options, rate = CASES[name]
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=0, **settings)
    with driver_class("balance", protocol)(port, clock, name=name, **options) as balance:
        balance.start_continuous()
        start = clock.now()
        shared_plant("cont").set_duty(0.5, clock.now())
        clock.sleep(4.0)
        got = balance.readings_since(start)
        assert len(got) == pytest.approx(4.0 * rate, abs=3)
        assert [r.t for r in got] == sorted(r.t for r in got)
        assert balance.latest() == got[-1]
        loaded_g = balance.latest().value * 1e3 if balance.latest().unit == "kg" else None
        if loaded_g is not None:
            assert loaded_g == pytest.approx(4.02, abs=0.05)  # Fig. 5.25 at 11 937 RPM
        balance.zero()  # pauses the stream, zeroes, resumes
        assert balance.continuous
        after = clock.now()
        clock.sleep(1.0)
        assert abs(balance.read().value) < 5e-5
        assert len(balance.readings_since(after)) >= rate * 0.5
        balance.stop_continuous()
        assert not balance.continuous and math.isfinite(balance.read().value)


def test_continuous_over_a_real_pty_uses_a_reader_thread_and_sees_the_unplug():
    clock = RealClock()
    emulator = MtSicsEmulator(plant=RigPlant(), seed=3, faults={"disconnect_at": 0.8})
    with PtyHost(emulator, clock=clock) as host:
        port = open_port(host.path, baudrate=9600, timeout=0)
        balance = driver_class("balance", "mtsics")(port, clock, name="pty-bal")
        balance.start_continuous()
        start = clock.now()
        clock.sleep(0.4)  # the caller does nothing; the reader thread fills the buffer
        assert len(balance.readings_since(start)) >= 3
        with pytest.raises(DeviceDisconnected) as err:
            for _ in range(200):
                balance.read(timeout=1.0)
        assert err.value.device == "pty-bal" and err.value.command == "stream"
        balance.close()
