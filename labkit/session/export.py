"""Readings files as tables: JSONL -> Parquet (pyarrow, which rerun-sdk brings) and CSV, one row
per reading with its stream's quantity and unit (:func:`labkit.readings.declared`)."""

from __future__ import annotations

import csv
import itertools
from pathlib import Path

from labkit.errors import SessionError
from labkit.readings import declared
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


#: rows converted at a time: the export's memory does not grow with the readings file
PARQUET_BATCH_ROWS = 20_000


def readings_to_parquet(src: Path, dest: Path, batch_rows: int = PARQUET_BATCH_ROWS) -> None:
    """``src`` (readings JSONL) as Parquet, written in batches of ``batch_rows`` rows."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from labkit.session.reader import iter_jsonl_lines

    schema = pa.schema([("t", pa.float64()), ("quantity", pa.string()), ("value", pa.float64()),
                        ("unit", pa.string()), ("stable", pa.bool_()), ("overload", pa.bool_()),
                        ("flags", pa.list_(pa.string())), ("raw", pa.string())])

    def batch(rows: list[dict]) -> pa.Table:
        columns = {c: [r.get(c) for r in rows] for c in PARQUET_COLUMNS}
        # files from before flags were recorded have none
        columns["flags"] = [list(f or []) for f in columns["flags"]]
        columns["raw"] = [r if r is not None else "" for r in columns["raw"]]
        return pa.table(columns, schema=schema)

    with pq.ParquetWriter(dest, schema) as writer:
        rows: list[dict] = []
        for _, row in declared(iter_jsonl_lines(src)):
            rows.append(row)
            if len(rows) >= batch_rows:
                writer.write_table(batch(rows))
                rows = []
        if rows:
            writer.write_table(batch(rows))


def readings_to_csv(src: Path, dest: Path, problems: list[str] | None = None) -> int:
    """Write ``src`` (readings JSONL) as CSV, row by row; returns the number of rows. Damaged
    lines are skipped and reported in ``problems``."""
    from labkit.session.reader import iter_jsonl_lines

    rows = declared(iter_jsonl_lines(src, problems))
    first = next(rows, None)  # an unreadable file fails here, before the CSV is created
    count = 0
    with open(dest, "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        for _, r in itertools.chain([first] if first is not None else [], rows):
            writer.writerow([";".join(r.get(c) or ()) if c == "flags" else r.get(c) for c in COLUMNS])
            count += 1
    return count


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
