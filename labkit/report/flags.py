"""The report's "Device flags" section: what the drivers noticed besides the values.

Every reading in ``readings/ROLE.jsonl`` carries ``flags`` (:meth:`labkit.readings.Reading.values_json`):
``device_reset`` (the device rebooted mid-run), ``tare_lost`` (its zero is no longer the run's
zero), ``overload``... A reading with a flag may be wrong in a way its value does not show,
so the report lists every flag with its count, the first flagged reading (time and raw bytes)
and its meaning (:data:`labkit.readings.READING_FLAGS`), and warns about the suspect ones.
"""

from __future__ import annotations

from pathlib import Path

from labkit.protocols.events import FlagTally
from labkit.readings import READING_FLAGS, Reading, declared
from labkit.report import markdown as md
from labkit.session.reader import iter_jsonl_lines


def session_flags(session: Path) -> tuple[FlagTally, dict[tuple[str, str], Reading]]:
    """Flag counts per role of a session's reading files, and the first reading of each flag."""
    tally = FlagTally()
    first: dict[tuple[str, str], Reading] = {}
    for path in sorted((session / "readings").glob("*.jsonl")):
        role = path.stem
        for _, row in declared(iter_jsonl_lines(path)):
            if not row.get("flags"):
                continue
            reading = Reading.from_json(row)
            tally.add(role, reading.flags, reading.t)
            for flag in reading.flags:
                first.setdefault((role, flag), reading)
    return tally, first


def flags_section(session: Path) -> list[str]:
    """Markdown lines: a table of flags (device, flag, count, first at, raw bytes) and a warning,
    or one line saying no reading carried a flag."""
    if not (session / "readings").is_dir():
        return []
    tally, first = session_flags(session)
    lines = ["## Device flags", ""]
    if not tally.counts:
        return lines + ["No reading carried a flag (no device reset, lost tare or overload).", ""]
    rows = [[role, flag, n, f"{first[(role, flag)].t:.3f}", f"`{first[(role, flag)].raw!r}`", meaning(flag)]
            for role, flags in sorted(tally.counts.items()) for flag, n in sorted(flags.items())]
    headers = ["device", "flag", "readings", "first at (s)", "first raw bytes", "meaning"]
    lines += [md.table(headers, rows), ""]
    suspect = sorted({f"{role}: {flag}" for role, flags in tally.counts.items() for flag in flags
                      if READING_FLAGS.get(flag, (True, ""))[0]})
    if suspect:
        lines += [f"> **Warning:** readings flagged {', '.join(suspect)} may be wrong in a way their "
                  "values do not show (a device that reset lost its zero); check the points recorded "
                  "after them.", ""]
    else:
        lines += ["Only informational flags: no reading is suspect.", ""]
    return lines


def meaning(flag: str) -> str:
    return READING_FLAGS.get(flag, (True, "not documented by labkit (treated as a warning)"))[1]
