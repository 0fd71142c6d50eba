"""Readings files as tables: JSONL -> Parquet (pyarrow, which rerun-sdk brings) and CSV."""

from __future__ import annotations

import csv
from pathlib import Path

from labkit.errors import SessionError
from labkit.session.paths import session_file
from labkit.session.reader import read_jsonl as read_checked

COLUMNS = ("t", "quantity", "value", "unit", "stable", "overload", "flags")
#: raw bytes (latin-1 text) go to Parquet only: a spreadsheet is for the numbers
PARQUET_COLUMNS = (*COLUMNS, "raw")


def read_jsonl(path: Path, problems: list[str] | None = None) -> list[dict]:
    """Objects of a JSONL file, bounded; a torn last line (crash mid-write) is skipped, any
    other damaged line too, reported in ``problems`` as ``file:line: reason``
    (:func:`labkit.session.reader.read_jsonl_lines`)."""
    return read_checked(path, problems)


def readings_to_parquet(src: Path, dest: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    rows = read_jsonl(src)
    columns = {c: [r.get(c) for r in rows] for c in PARQUET_COLUMNS}
    # files from before flags were recorded have none
    columns["flags"] = pa.array([list(f or []) for f in columns["flags"]], type=pa.list_(pa.string()))
    columns["raw"] = [r if r is not None else "" for r in columns["raw"]]
    table = pa.table(columns)
    pq.write_table(table, dest)


def readings_to_csv(src: Path, dest: Path, problems: list[str] | None = None) -> int:
    """Write ``src`` (readings JSONL) as CSV; returns the number of rows. Damaged lines are
    skipped and reported in ``problems``."""
    rows = read_jsonl(src, problems)
    with open(dest, "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        for r in rows:
            writer.writerow([";".join(r.get(c) or ()) if c == "flags" else r.get(c) for c in COLUMNS])
    return len(rows)


def export_csv(session: Path, problems: list[str] | None = None) -> list[Path]:
    """Export every device's readings of a session to ``readings/ROLE.csv`` (damaged lines
    skipped, reported in ``problems`` as ``file:line: reason``)."""
    out = []
    for found in sorted((session / "readings").glob("*.jsonl")):
        src = session_file(session, "readings", found.name)  # a symlink out of the session is refused
        name = found.with_suffix(".csv").name
        if Path(session, "readings", name).is_symlink():  # the path as it stands, before resolving
            raise SessionError(f"{session}/readings/{name}: is a symbolic link; labkit writes no "
                               "file through a link (a session from elsewhere?): remove it")
        dest = session_file(session, "readings", name)
        readings_to_csv(src, dest, problems)
        out.append(dest)
    return out
