"""firmware/labkit_tach compiled and run on a simulated ATmega328P, fed pulse trains on pin 2
(INT0), read through ``labkit probe tach --protocol labkit_tach`` on its pseudo-terminal.

The pulse train is exact in simulated time, so the sketch's reading is checked against the
RPM it was given: within 0.5 % for a clean train (micros() has 4 us steps, averaged over a
100 ms window), 2 % with 2 % period jitter, 1 % with every 7th pulse missing (the sketch
bridges a missing pulse and flags the window ``noisy``).
"""

from __future__ import annotations

import json

import pytest

from labkit.cli import main
from labkit.units import RAD_S_PER_RPM

pytestmark = pytest.mark.timeout(120)


def probe(capsys, pty: str, samples: int, *options: str) -> list[dict]:
    code = main(["probe", "tachometer", "--protocol", "labkit_tach", "--port", pty,
                 "--samples", str(samples), "--json", *options])
    out, err = capsys.readouterr()
    assert code == 0, err
    return [json.loads(line) for line in out.splitlines()]


# (rpm, ppr, jitter, miss every Nth, relative tolerance, flags expected on every reading)
TRAINS = [
    (600.0, 1, 0.0, 0, 0.005, set()),
    (6000.0, 1, 0.0, 0, 0.005, set()),
    (30000.0, 2, 0.0, 0, 0.005, set()),
    (100000.0, 1, 0.0, 0, 0.005, set()),
    (30000.0, 1, 0.02, 0, 0.02, set()),
    (12000.0, 1, 0.0, 7, 0.01, {"noisy"}),
]


def test_pulse_trains_from_0_to_100000_rpm(simavr, capsys):
    sim = simavr("labkit_tach")
    readings = probe(capsys, sim.pty, 3)          # no pulses yet: zero speed, said so
    assert all(r["value"] == 0.0 and "zero_speed" in r["flags"] for r in readings[-2:])
    for rpm, ppr, jitter, miss, tolerance, flags in TRAINS:
        sim.pulses(rpm, ppr, jitter, miss)
        # the first window after the change mixes two speeds: judge the last three
        readings = probe(capsys, sim.pty, 6, "-o", f"ppr={ppr}")[-3:]
        for reading in readings:
            measured = reading["value"] / RAD_S_PER_RPM
            assert measured == pytest.approx(rpm, rel=tolerance), (rpm, ppr, jitter, miss, reading)
            assert flags <= set(reading["flags"]), reading
            assert reading["stable"] == (not flags), reading
    sim.pulses(0.0)
    readings = probe(capsys, sim.pty, 14, "-o", "ppr=1")   # the sketch's 1 s zero-speed timeout
    assert readings[-1]["value"] == 0.0 and "zero_speed" in readings[-1]["flags"]
