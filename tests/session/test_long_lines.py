"""Line limits of a session's JSONL files (labkit.session.reader): an event line may be as long as
results.json may be (the results event repeats it: 2.5 MB for a 4 736-point sweep, which the
1 MB reading limit once refused as "damaged"); a reading line is bounded at 1 MB; an over-long
line is skipped without reading it whole, and the line after it is read."""

from __future__ import annotations

import json

from labkit.session import reader
from labkit.session.reader import iter_jsonl_lines


def _results_event(points: int) -> dict:
    row = {"step": 0, "target_rpm": 6000.0, "speed_rpm": 6001.234567, "force_gf": 1.234567891,
           "force_std_gf": 0.0123456789, "n": 42, "zero_drift_gf": 0.22, "flags": []}
    return {"type": "results", "t": 1.0, "results": {"points": [dict(row, step=k) for k in range(points)]}}


def test_a_results_event_longer_than_a_megabyte_is_read(tmp_path):
    events = tmp_path / "events.jsonl"
    big = _results_event(12_000)
    events.write_text(json.dumps({"type": "start"}) + "\n" + json.dumps(big) + "\n"
                      + json.dumps({"type": "stop"}) + "\n")
    assert len(json.dumps(big)) > 1_500_000
    problems: list[str] = []
    lines = list(iter_jsonl_lines(events, problems))
    assert problems == []
    assert [e["type"] for _, e in lines] == ["start", "results", "stop"]
    assert len(lines[1][1]["results"]["points"]) == 12_000


def test_a_reading_line_longer_than_a_megabyte_is_a_damaged_line(tmp_path):
    readings = tmp_path / "balance.jsonl"
    readings.write_text(json.dumps({"t": 0.0, "value": 1.0}) + "\n"
                        + json.dumps({"t": 1.0, "junk": "x" * 1_200_000}) + "\n"
                        + json.dumps({"t": 2.0, "value": 2.0}) + "\n")
    problems: list[str] = []
    lines = list(iter_jsonl_lines(readings, problems))
    assert [n for n, _ in lines] == [1, 3]
    assert problems == [f"{readings}:2: damaged line skipped (longer than 1000000 bytes)"]


def test_an_event_line_over_the_limit_is_skipped_and_the_next_one_read(tmp_path, monkeypatch):
    monkeypatch.setattr(reader, "MAX_EVENT_LINE_BYTES", 1000)
    events = tmp_path / "events.jsonl"
    events.write_text(json.dumps(_results_event(5_000)) + "\n" + json.dumps({"type": "stop"}) + "\n")
    problems: list[str] = []
    lines = list(iter_jsonl_lines(events, problems))
    assert [(n, e["type"]) for n, e in lines] == [(2, "stop")]
    assert problems == [f"{events}:1: damaged line skipped (longer than 1000 bytes)"]
