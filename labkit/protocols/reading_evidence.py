"""What a faithful replay checks of ``readings/ROLE.jsonl`` (issue 27, *sessions you can trust*).

An exact replay reproduces every reading bit for bit (:mod:`labkit.protocols.replay_evidence`).
A faithful replay (a real-clock session) cannot: its polls fall at other moments, so a polled
device (the balance) gives a few readings more or fewer than the recording (188 against 192 in
``recordings/sessions/real-speed-sweep``). Each recorded reading is instead held against the
device's cassette directly:

* **its bytes arrived**: the reading's ``raw`` bytes are found in the cassette's received
  bytes, in the order of the readings file, having arrived at most :data:`MAX_LAG_S` before the
  reading's time ``t`` and not after it (within :data:`CLOCK_EPS_S`);
* **its value follows from its bytes**: the same bytes parsed by the replay (the same driver,
  the same options) gave the same ``value`` and ``unit``; bytes the replay never parsed (a
  poll it did not make) are parsed by the analysis-only re-parser of the device's protocol
  (:data:`labkit.protocols.reanalyse.REPARSERS`), else their value is not checked.

What cannot be seen: a reading removed from the file (the points are checked against the
replay's within tolerance instead), and an edit that keeps bytes, time and value consistent
with another frame the cassette holds.
"""

from __future__ import annotations

import bisect
import math
from array import array
from collections.abc import Iterable
from pathlib import Path
from typing import Any

#: a reading is parsed this long at most after its last byte arrived (the readers parse a frame
#: at once: at most 1.2 ms in the shipped real-clock recordings, the busy PC's included)
MAX_LAG_S = 0.5
#: clock readings of two threads of one process may disagree by this much
CLOCK_EPS_S = 0.01
#: at most this many differences are listed per file
MAX_LISTED = 5


class RxStream:
    """A cassette's received bytes as one stream, each byte's arrival on the recording's clock."""

    def __init__(self, path: Path) -> None:
        from labkit.io.cassette import CassetteReader

        reader = CassetteReader(path)  # read as a stream: the bytes and 24 bytes per chunk kept
        origin = reader.header.get("clock_origin")
        self.origin = float(origin) if isinstance(origin, int | float) else 0.0
        data = bytearray()
        self.ends = array("q")   # offset after each chunk's last byte
        self.times = array("d")
        self.lines = array("q")
        for e in reader:
            if e["dir"] == "rx":
                data += e["bytes"]
                self.ends.append(len(data))
                self.times.append(self.origin + float(e["t"]))
                self.lines.append(int(e.get("line", 0)))
        self.data = bytes(data)

    def arrival(self, end: int) -> tuple[float, int]:
        """When the byte before offset ``end`` arrived, and the cassette line that brought it."""
        i = bisect.bisect_left(self.ends, end)
        return self.times[i], self.lines[i]

    def find(self, raw: bytes, start: int, t: float) -> int | None:
        """The end offset of the first copy of ``raw`` at or after ``start`` that arrived in
        ``[t - MAX_LAG_S, t + CLOCK_EPS_S]``; None if there is none."""
        at = self.data.find(raw, start)
        while at >= 0:
            arrived, _ = self.arrival(at + len(raw))
            if arrived > t + CLOCK_EPS_S:
                return None
            if arrived >= t - MAX_LAG_S:
                return at + len(raw)
            at = self.data.find(raw, at + 1)
        return None


def _same_number(a: Any, b: Any) -> bool:
    if isinstance(a, int | float) and isinstance(b, int | float):
        return a == b or (math.isnan(a) and math.isnan(b))
    return a == b


def _expected(rec: dict[str, Any], parsed: dict[str, tuple[Any, Any]],
              reparse: Any) -> tuple[Any, Any] | None:
    raw = str(rec.get("raw", ""))
    if raw in parsed:
        return parsed[raw]
    if reparse is None:
        return None
    try:
        again = reparse(float(rec["t"]), raw.encode("latin-1"))
    except Exception:  # noqa: BLE001 - bytes no parser accepts: said as a difference below
        return (None, None)
    return (again.value, again.unit)


def diff_readings_faithful(device: Any, parsed: dict[str, tuple[Any, Any]],
                           recorded: Iterable[tuple[int, dict[str, Any]]], cassette_path: Path,
                           file: str) -> list[str]:
    """Each recorded reading of ``device`` (``(file line, reading)``, read as they come) against
    its cassette (module docstring); ``parsed``: the replay's value and unit by raw bytes."""
    from labkit.protocols.reanalyse import REPARSERS

    stream = RxStream(cassette_path)
    reparse = REPARSERS.get(device.protocol)
    out: list[str] = []
    start = 0
    for line, rec in recorded:
        raw, t = rec.get("raw"), rec.get("t")
        if not isinstance(raw, str) or not raw or not isinstance(t, int | float):
            continue  # a reading without its bytes (an older labkit): nothing to hold it against
        end = stream.find(raw.encode("latin-1"), start, float(t))
        if end is None:
            out.append(f"{file}:{line}: this reading's bytes {raw!r} did not arrive in {cassette_path} "
                       f"in the {MAX_LAG_S:g} s before its time {t!r}: edited?")
        else:
            start = end
            expected = _expected(rec, parsed, reparse)
            if expected is not None and not (_same_number(rec.get("value"), expected[0])
                                             and rec.get("unit") == expected[1]):
                _, cassette_line = stream.arrival(end)
                out.append(f"{file}:{line}: value {rec.get('value')!r} {rec.get('unit')} does not follow "
                           f"from its bytes {raw!r} ({cassette_path.name}:{cassette_line} gives "
                           f"{expected[0]!r} {expected[1]}): edited?")
        if len(out) >= MAX_LISTED:
            out.append(f"{file}: further differences not listed")
            break
    return out


def faithful_reading_diffs(record: Any, rig: Any, parsed: dict[str, dict[str, tuple[Any, Any]]]) -> list[str]:
    """Every device's readings file against its cassette, both read as streams; ``parsed``: by
    device, the value and unit the replay parsed from each reading's raw bytes
    (:attr:`labkit.protocols.replay_evidence.Evidence.parsed`)."""
    from labkit.readings import declared
    from labkit.session.paths import session_file
    from labkit.session.reader import iter_jsonl_lines

    out: list[str] = []
    for role, dev in sorted(rig.devices.items()):
        file = record.path / "readings" / f"{role}.jsonl"
        cassette = record.path / "cassettes" / f"{role}.jsonl"
        if file.is_file() and cassette.is_file():
            path = session_file(record.path, "readings", f"{role}.jsonl")
            recorded = declared(iter_jsonl_lines(path, record.problems))   # units from the descriptor
            out += diff_readings_faithful(dev, parsed.get(role, {}), recorded, cassette, str(file))
    return out
