"""``labkit probe``: identify + N JSON lines; device faults end in one line and exit 2.
Runs the real CLI entry point against emulators (sim://, a real pty) and a cassette."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.emulators.balances import MtSicsEmulator
from labkit.emulators.rig_plant import RigPlant
from labkit.io.clock import RealClock, VirtualClock, use_clock
from labkit.io.pty_host import PtyHost

CASSETTES = Path(__file__).resolve().parents[1] / "recordings" / "cassettes"
KEYS = {"t", "value", "unit", "stable", "overload", "flags", "raw"}


def probe(capsys, *argv: str) -> tuple[int, list[str], str]:
    code = main(["probe", *argv])
    captured = capsys.readouterr()
    return code, captured.out.splitlines(), captured.err


@pytest.mark.parametrize("protocol,url,extra", [
    ("mtsics", "sim://mtsics?seed=1", []),
    ("and_std", "sim://and_std?seed=1&unit=N", []),
    ("line_regex", "sim://hx711?preset=bogde_full&startup_s=0.1&rate_hz=10", ["-o", "preset=bogde_full"]),
])
def test_probe_prints_one_json_reading_per_line(capsys, protocol, url, extra):
    code, out, err = probe(capsys, "balance", "--protocol", protocol, "--port", url,
                           "--samples", "4", "--json", *extra)
    assert code == 0, err
    readings = [json.loads(line) for line in out]
    assert len(readings) == 4
    for reading in readings:
        assert KEYS <= set(reading)
        assert reading["unit"] in ("kg", "N") and math.isfinite(reading["value"])
    assert [r["t"] for r in readings] == sorted(r["t"] for r in readings)
    assert json.loads(err.splitlines()[0])["protocol"] == protocol  # identification on stderr


def test_probe_over_a_real_pty_with_identification_header(capsys):
    emulator = MtSicsEmulator(plant=RigPlant(), seed=2)
    with PtyHost(emulator, clock=RealClock()) as host:
        code, out, _ = probe(capsys, "balance", "--protocol", "mtsics", "--port", host.path,
                             "--samples", "2")
    assert code == 0
    header = json.loads(out[0].removeprefix("# "))
    assert header["serial"] == "B207696838" and header["settings"]["baudrate"] == 9600
    assert len(out) == 3


def test_probe_overload_prints_null_and_flag(capsys):
    code, out, _ = probe(capsys, "balance", "--protocol", "mtsics", "--port",
                         "sim://mtsics?faults=overload:1", "--samples", "1", "--json")
    reading = json.loads(out[0])
    assert code == 0 and reading["value"] is None and reading["overload"] is True


def test_probe_wrong_parity_says_so_in_one_line(capsys):
    with use_clock(VirtualClock()):  # the 2 s timeout passes on a virtual clock
        code, out, err = probe(capsys, "balance", "--protocol", "and_std", "--port", "sim://and_std",
                               "--parity", "N", "--bytesize", "8", "--samples", "1")
    assert code == 2 and out == []
    lines = err.strip().splitlines()
    assert len(lines) == 1
    assert "balance and_std at sim://and_std" in lines[0] and "check baud rate/parity" in lines[0]
    assert "command 'C'" in lines[0] and "last bytes" in lines[0]


def test_probe_unplug_mid_read_exits_2_naming_command(capsys):
    code, out, err = probe(capsys, "balance", "--protocol", "mtsics", "--port",
                           "sim://mtsics?faults=disconnect_at:0.2", "--samples", "1000")
    assert code == 2 and 0 < len(out) < 1000
    assert "port disconnected" in err and "command 'SI'" in err


def test_probe_replays_a_cassette(capsys):
    # the recorded session starts with I2, I4, SI: the probe's own order
    code, out, err = probe(capsys, "balance", "--protocol", "mtsics", "--port",
                           f"replay://{CASSETTES / 'balance-mtsics.jsonl'}?mode=timed",
                           "--samples", "1", "--json")
    assert code == 0, err
    assert json.loads(out[0])["raw"] == "S D      -0.00 g"


def test_probe_unknown_protocol_and_bad_option(capsys):
    code, _, err = probe(capsys, "balance", "--protocol", "nope", "--port", "sim://mtsics")
    assert code == 2 and "known: " in err and "mtsics" in err
    code, _, err = probe(capsys, "balance", "--protocol", "line_regex", "--port", "sim://hx711",
                         "-o", "preset=unknown")
    assert code == 2 and "preset 'unknown'" in err
    code, _, err = probe(capsys, "tachometer", "--protocol", "labkit_tach", "--port", "sim://labkit_tach",
                         "-o", "pulses_per_rev=2")
    assert code == 2 and "unknown option 'pulses_per_rev' for labkit_tach; known: " in err
    assert "ppr" in err and len(err.strip().splitlines()) == 1


def test_probe_motor_reads_status_and_never_starts_it(capsys):
    code, out, err = probe(capsys, "motor", "--protocol", "pololu_smc", "--port",
                           "sim://pololu_smc?plant=probe-motor", "--samples", "2", "--json")
    if code == 2 and "no motor driver" in err:
        pytest.skip("pololu_smc driver not in this tree yet")
    assert code == 0, err
    statuses = [json.loads(line) for line in out]
    assert all(s["value"] == 0 for s in statuses)
    # at rest the SMC reports its safe-start bit: listed, but no overload (issue 27)
    assert all(s["overload"] is False and "safe_start_violation" in s["errors"] for s in statuses), statuses
    from labkit.emulators.plant import shared_plant

    assert shared_plant("probe-motor").motor("rotor").duty == 0.0


def test_probe_continuous_reads_the_sir_stream(capsys):
    with use_clock(VirtualClock()):
        code, out, err = probe(capsys, "balance", "--protocol", "mtsics", "--port", "sim://mtsics?seed=3",
                               "--samples", "6", "--continuous", "--json")
    assert code == 0, err
    times = [json.loads(line)["t"] for line in out]
    gaps = [b - a for a, b in zip(times[1:], times[2:], strict=False)]  # the first line answers SIR
    assert gaps == pytest.approx([0.05] * 4, abs=0.006)  # then the emulated balance streams at 20 Hz


def test_probe_shows_a_device_reset_in_the_reading_flags(capsys):
    """An HX711 sketch that reboots mid-session prints its banner again and re-tares: the next
    reading says so (``flags``), once."""
    code, out, err = probe(capsys, "balance", "--protocol", "line_regex", "-o", "preset=bogde_full",
                           "--port", "sim://hx711?preset=bogde_full&rate_hz=10&startup_s=0.1"
                           "&faults=reset_at:1.5",
                           "--samples", "40", "--json")
    assert code == 0, err
    flags = [set(json.loads(line)["flags"]) for line in out]
    flagged = [i for i, f in enumerate(flags) if "device_reset" in f]
    assert len(flagged) == 1 and "tare_lost" in flags[flagged[0]]
    assert flagged[0] > 0 and all("stability_unknown" in f for f in flags)  # the sketch has no flag
