"""Acceptance (issue 12): a device fault that sets a flag reaches every record of the run.

An emulated Fig. 5.25 sweep whose balance is an Arduino + HX711 sketch (``line_regex`` driver,
``hx711_adc`` preset) that reboots 20 s into the run (the emulator's ``reset_at`` fault, see
tests/devices/test_hx711_faults.py). The driver flags the first line after the reboot
``device_reset`` and ``tare_lost``; that flag must be in the session's reading file (with the
raw bytes of the line), in ``labkit report``, in what ``labkit replay`` prints, and in the .rrd
read back with rerun's own reader.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.rig import bundled_rig_path
from labkit.stream.readback import column

RESET_AT_S = 20.0


def hx711_rig(tmp_path: Path) -> Path:
    """emulated-fig525 with its MT-SICS balance replaced by an HX711 sketch that reboots."""
    text = bundled_rig_path("emulated-fig525").read_text()
    old = '''protocol = "mtsics"
port = "sim://mtsics?seed=3&plant=model-fig525&role=balance"
serial = { baudrate = 9600, timeout = 0.5 }'''
    assert old in text
    new = f'''protocol = "line_regex"
options = {{ preset = "hx711_adc" }}
port = "sim://hx711?seed=3&plant=model-fig525&role=balance&preset=hx711_adc&startup_s=0.3&faults=reset_at:{RESET_AT_S}"
serial = {{ baudrate = 57600, timeout = 0.5 }}'''
    path = tmp_path / "hx711-reboot.toml"
    path.write_text(text.replace(old, new).replace('name = "emulated-fig525"', 'name = "hx711-reboot"'))
    return path


RUN_WARNING: list[str] = []


@pytest.fixture(scope="module")
def session(tmp_path_factory) -> tuple[Path, Path]:
    """(session directory, its .rrd) of the sweep, recorded once for the module's tests."""
    root = tmp_path_factory.mktemp("hx711-reboot")
    rrd = root / "run.rrd"
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert main(["run", str(hx711_rig(root)), "speed-sweep", "--set", "speeds_rpm=6000:20000:3500",
                     "--set", "record_s=1", "--sessions", str(root / "s"), "--no-progress",
                     "--rerun", f"save:{rrd}"]) == 0
    RUN_WARNING.append(err.getvalue())
    [path] = (root / "s").iterdir()
    return path, rrd


def test_labkit_run_warns_about_the_suspect_flags_only(session):
    [err] = RUN_WARNING
    [line] = [x for x in err.splitlines() if "warning: readings flagged" in x]
    assert "balance: device_reset x1" in line and "balance: tare_lost x1" in line
    assert "stability_unknown" not in line and "zero_speed" not in line


def test_the_reading_file_has_the_flag_and_the_raw_line(session):
    path, _ = session
    lines = [json.loads(line) for line in (path / "readings" / "balance.jsonl").read_text().splitlines()]
    assert lines[0]["type"] == "descriptor" and lines[0]["unit"] in ("kg", "N")   # the stream's units, once
    rows = lines[1:]
    flagged = [r for r in rows if "device_reset" in r["flags"]]
    assert len(flagged) == 1                       # flagged once, the line after the reboot
    [reset] = flagged
    assert "tare_lost" in reset["flags"] and reset["t"] > RESET_AT_S
    assert reset["raw"].startswith("Load_cell output val:")   # the sketch's line, as received
    assert all("device_reset" not in r["flags"] for r in rows if r["t"] < RESET_AT_S)


def test_the_flag_survives_parquet(session):
    import pyarrow.parquet as pq

    path, _ = session
    table = pq.read_table(path / "readings" / "balance.parquet").to_pylist()
    assert sum("device_reset" in r["flags"] for r in table) == 1
    assert all(r["raw"] for r in table)


def test_report_lists_the_flag_with_its_time_and_bytes(session, tmp_path):
    path, _ = session
    assert main(["report", str(path), "--out", str(tmp_path / "r")]) == 0
    text = (tmp_path / "r" / "report.md").read_text()
    section = text.split("## Device flags")[1].split("\n## ")[0]
    [row] = [line for line in section.splitlines() if "| device_reset |" in line]
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[0] == "balance" and cells[2] == "1" and float(cells[3]) > RESET_AT_S
    assert "Load_cell output val:" in cells[4]
    assert "| tare_lost |" in section
    [warning] = [line for line in section.splitlines() if "Warning" in line]
    assert "balance: device_reset" in warning and "balance: tare_lost" in warning
    assert "stability_unknown" not in warning and "zero_speed" not in warning   # informational


def test_replay_prints_the_flag(session, capsys):
    path, _ = session
    assert main(["replay", str(path)]) == 0
    out = capsys.readouterr().out
    assert "device flags:" in out and "balance: device_reset x1" in out


def test_the_rrd_read_back_has_the_flag_at_its_time(session):
    path, rrd = session
    times, flags = column(rrd, "/rig/balance/frame", "flags", "time")
    _, raws = column(rrd, "/rig/balance/frame", "raw", "time")
    assert len(flags) == len(raws) > 10
    flagged = [(t, f) for t, f in zip(times, flags, strict=True) if "device_reset" in str(f)]
    assert len(flagged) == 1
    [(when, [text])] = flagged
    assert set(text.split(";")) >= {"device_reset", "tare_lost"}
    assert when.total_seconds() > RESET_AT_S          # the time axis starts at the run's start (t=0)
    assert any("Load_cell output val:" in str(r) for r in raws)
