"""Readings exported in batches (docs/reference/session-size.md): the Parquet file holds every row of the
JSONL file, in order, whatever the batch size; damaged lines are left out of both exports."""

from __future__ import annotations

import csv
import json

import pyarrow.parquet as pq
import pytest

from labkit.session.export import readings_to_csv, readings_to_parquet


def reading(i: int) -> dict:
    return {"t": 0.05 * i, "quantity": "mass", "value": None if i == 3 else 1.5 * i, "unit": "g",
            "stable": i % 2 == 0, "overload": i == 3, "flags": ["tare_lost"] if i == 4 else [],
            "raw": f"S S {1.5 * i:9.3f} g\r\n"}


@pytest.mark.parametrize("batch_rows", [1, 2, 3, 20_000])
def test_parquet_holds_every_row_whatever_the_batch(tmp_path, batch_rows):
    src = tmp_path / "balance.jsonl"
    rows = [reading(i) for i in range(7)]
    src.write_text("".join(json.dumps(r) + "\n" for r in rows[:5]) + "{torn\n"
                   + "".join(json.dumps(r) + "\n" for r in rows[5:]))
    readings_to_parquet(src, tmp_path / "balance.parquet", batch_rows=batch_rows)
    assert pq.read_table(tmp_path / "balance.parquet").to_pylist() == rows
    problems: list[str] = []
    assert readings_to_csv(src, tmp_path / "balance.csv", problems) == 7
    with open(tmp_path / "balance.csv", newline="") as f:
        table = list(csv.reader(f))
    assert len(table) == 8 and table[5][6] == "tare_lost" and table[4][2] == ""
    assert problems == [f"{src}:6: damaged line skipped (not JSON (Expecting property name enclosed in "
                        "double quotes at line 1 column 2))"]
