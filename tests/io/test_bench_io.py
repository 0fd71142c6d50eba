"""labkit bench io runs and reports its fields (timings are printed, never asserted)."""

from __future__ import annotations

import json

from labkit.cli.bench_io import main, parser_rate
from labkit.devices.registry import parser_benchmarks


def test_bench_io_reports_every_registered_parser_and_the_replay_fields(capsys):
    assert main(["--minutes", "0.1", "--parser-budget", "0.001", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {row["protocol"] for row in out["parsers"]} == set(parser_benchmarks())
    assert all("frames_per_s" in row for row in out["parsers"]), out["parsers"]
    replay = out["replay"]
    assert replay["session_s"] == 6.0
    assert replay["readings_identical"] is True
    assert replay["balance_readings"] == 6  # one SI poll per second
    assert {"record_wall_s", "replay_wall_s", "replay_ratio", "cassette_events"} <= set(replay)


def test_text_report_names_the_ratio(capsys):
    assert main(["--minutes", "0.05", "--parser-budget", "0.001"]) == 0
    text = capsys.readouterr().out
    assert "frames/s" in text and "x real time" in text and "identical to the recording: yes" in text


def test_parser_rate_counts_calls():
    calls = []
    rate = parser_rate(calls.append, b"x", budget_s=0.001, repeats=2)
    assert rate > 0 and len(calls) >= 2
