"""labkit ports and labkit emulate, through the command line."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import serial
from serial.tools.list_ports_common import ListPortInfo

from labkit.cli.emulate import main as emulate_main
from labkit.cli.ports import hwgrep_url, port_row
from labkit.cli.ports import main as ports_main

REPO = Path(__file__).resolve().parents[2]


def usb_port(device: str, vid: int, pid: int, serial_number: str | None) -> ListPortInfo:
    info = ListPortInfo(device, skip_link_detection=True)
    info.vid, info.pid, info.serial_number, info.location = vid, pid, serial_number, "1-1.2:1.0"
    info.product = "FT232R USB UART"
    info.apply_usb_info()  # pyserial's own hwid format, which hwgrep:// searches
    return info


def test_hwgrep_url_finds_exactly_the_adapter_with_that_serial_number():
    mine = usb_port("/dev/ttyUSB0", 0x0403, 0x6001, "A10K+9Z")
    twin = usb_port("/dev/ttyUSB1", 0x0403, 0x6001, "B77")
    url = port_row(mine)["url"]
    assert url.startswith("hwgrep://0403:6001")
    pattern = url[len("hwgrep://"):]
    assert re.search(pattern, mine.hwid, re.I)
    assert not re.search(pattern, twin.hwid, re.I)


def test_ports_without_usb_ids_keep_their_path_and_ids_without_serial_use_vid_pid():
    assert hwgrep_url("/dev/ttyS0", None, None, None) == "/dev/ttyS0"
    assert hwgrep_url("/dev/ttyACM0", 0x2341, 0x0043, None) == "hwgrep://2341:0043"
    row = port_row(usb_port("/dev/ttyUSB3", 0x1FFB, 0x00A1, None))
    assert row["vid_pid"] == "1FFB:00A1" and row["location"] == "1-1.2:1.0"


def test_labkit_ports_json_lists_what_pyserial_sees(capsys):
    from serial.tools import list_ports

    assert ports_main(["--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["device"] for r in rows] == sorted(p.device for p in list_ports.comports())
    for row in rows:
        assert {"device", "description", "vid_pid", "serial_number", "location", "url"} <= set(row)


def test_emulate_serves_a_rigs_devices_on_ptys_that_plain_pyserial_can_use():
    proc = subprocess.Popen(
        [sys.executable, "-m", "labkit.cli.emulate", str(REPO / "rigs" / "emulated-fig525.toml"),
         "--device", "spare=sim://mtsics?seed=9", "--seconds", "20", "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO,
    )
    try:
        paths = json.loads(proc.stdout.readline())
        assert set(paths) == {"rotor_motor", "rotor_tach", "balance", "spare"}
        assert all(p.startswith("/dev/pts/") for p in paths.values())
        assert len(set(paths.values())) == 4
        with serial.Serial(paths["balance"], 9600, timeout=3.0) as port:
            port.write(b"SI\r\n")  # MT-SICS: send the weight now, stable or not
            lines = [port.read_until(b"\n")]
            while not lines[-1].startswith(b"S ") and len(lines) < 3:  # may follow a banner
                lines.append(port.read_until(b"\n"))
        assert lines[-1].startswith(b"S ") and lines[-1].endswith(b" g\r\n"), lines
    finally:
        proc.terminate()
        proc.wait(timeout=10)
        proc.stdout.close()
        proc.stderr.close()


def test_emulate_rejects_a_device_that_is_not_sim(capsys):
    assert emulate_main(["--device", "balance=/dev/ttyUSB0", "--seconds", "0"]) == 2
    assert "expected --device ROLE=sim://" in capsys.readouterr().err
