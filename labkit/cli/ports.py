"""``labkit ports [--json]``: the serial ports and cameras attached to this machine, with rig-file URLs.

For each port: device path, description, USB VID:PID, serial number, location, and a
``hwgrep://`` URL that finds the same adapter again after it re-enumerates (ttyUSB0 today,
ttyUSB1 tomorrow); put that URL in the rig file's ``port`` key. Cameras (``/dev/video*``,
with the name the kernel gives them) are listed with a ``v4l2://`` URL asking for MJPEG
(docs/reference/camera.md).
"""

from __future__ import annotations

import argparse
import json
import re
from typing import Any

from labkit.cli.summaries import COMMAND_SUMMARIES

NO_PORTS = (
    "no serial ports found. Plug in the USB-serial adapter and run again; on Linux check "
    "`dmesg | tail` and that you are in the 'dialout' group. For emulated devices use "
    "`labkit emulate RIG`. No camera (/dev/video*) either."
)


def hwgrep_url(device: str, vid: int | None, pid: int | None, serial_number: str | None) -> str:
    """The most specific stable URL for a port: USB serial number, else VID:PID, else the path.

    ``hwgrep://`` matches its regular expression against each port's path, description and
    hardware id (``USB VID:PID=0403:6001 SER=A1B2 LOCATION=1-1.2``), case-insensitively.
    """
    if vid is None or pid is None:
        return device
    ids = f"{vid:04X}:{pid:04X}"
    if serial_number:
        return f"hwgrep://{ids}.*SER={re.escape(serial_number)}"
    return f"hwgrep://{ids}"


def port_row(info: Any) -> dict[str, Any]:
    """One ``serial.tools.list_ports`` entry as a JSON-friendly dict."""
    vid, pid = getattr(info, "vid", None), getattr(info, "pid", None)
    return {
        "device": info.device,
        "description": info.description,
        "vid_pid": f"{vid:04X}:{pid:04X}" if vid is not None and pid is not None else None,
        "serial_number": info.serial_number,
        "manufacturer": info.manufacturer,
        "location": info.location,
        "hwid": info.hwid,
        "url": hwgrep_url(info.device, vid, pid, info.serial_number),
    }


def list_port_rows() -> list[dict[str, Any]]:
    from serial.tools import list_ports

    return [port_row(info) for info in sorted(list_ports.comports(), key=lambda i: i.device)]


def list_camera_rows(dev: str = "/dev", sysfs: str = "/sys/class/video4linux") -> list[dict[str, Any]]:
    """``/dev/video*`` devices (a UVC camera usually has two: frames and metadata; the first
    of the pair gives frames) as rows like the serial ports'."""
    from pathlib import Path

    rows = []
    for node in sorted(Path(dev).glob("video*"), key=lambda p: (len(p.name), p.name)):
        try:
            name = (Path(sysfs) / node.name / "name").read_text(encoding="utf-8").strip()
        except OSError:
            name = "video device"
        rows.append({"device": str(node), "description": name, "vid_pid": None, "serial_number": None,
                     "manufacturer": None, "location": None, "hwid": "video4linux",
                     "url": f"v4l2://{node}?fourcc=MJPG"})
    return rows


def format_table(rows: list[dict[str, Any]]) -> str:
    """Rows as an aligned text table (the non-JSON output)."""
    headers = ("device", "description", "vid_pid", "serial_number", "location", "url")
    cells = [[str(r.get(h) or "-") for h in headers] for r in rows]
    widths = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(headers)]
    lines = ["  ".join(h.upper().ljust(w) for h, w in zip(headers, widths, strict=True))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) for row in cells]
    return "\n".join(line.rstrip() for line in lines)


def run(args: argparse.Namespace) -> int:
    rows = list_port_rows() + list_camera_rows()
    if args.json:
        print(json.dumps(rows, indent=2))
    elif not rows:
        print(NO_PORTS)
    else:
        print(format_table(rows))
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("ports", help=COMMAND_SUMMARIES["ports"],
                            description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print a JSON list instead of a table")
    parser.set_defaults(func=run)


def main(argv: list[str] | None = None) -> int:
    """``python -m labkit.cli.ports [--json]``: the same command without loading every other one."""
    import sys

    parser = argparse.ArgumentParser(prog="labkit")
    register(parser.add_subparsers(dest="command"))
    return run(parser.parse_args(["ports", *(sys.argv[1:] if argv is None else argv)]))


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
