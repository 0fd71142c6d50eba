"""Hypothesis fuzzing of the input parsers touched by issue 17: any bytes give rows or one
expected error naming the file, never another exception."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from labkit.errors import DataFileError, RigFileError
from labkit.fit.data import load_table
from labkit.rig import parse_rig
from labkit.session.reader import parse_json_bytes, read_jsonl_lines

FUZZ = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
LINES = st.lists(st.one_of(
    st.binary(max_size=40),
    st.sampled_from([b'{"type":"point","point":{"step":1}}', b"[1,2]", b"{", b"[" * 200, b"null", b"{}"]),
    st.dictionaries(st.text(max_size=5), st.integers()).map(lambda d: json.dumps(d).encode()),
), max_size=12)


@FUZZ
@given(LINES, st.booleans())
def test_jsonl_reader_keeps_objects_and_names_every_other_line(lines, newline_at_end):
    data = b"\n".join(lines) + (b"\n" if newline_at_end else b"")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "events.jsonl"
        path.write_bytes(data)
        problems: list[str] = []
        rows = read_jsonl_lines(path, problems)
    assert all(isinstance(row, dict) for _, row in rows)
    assert all(p.startswith(f"{path}:") and "damaged line skipped" in p for p in problems)
    physical = data.split(b"\n")
    for number, row in rows:
        assert json.loads(physical[number - 1]) == row
    # every non-blank line is a row, a reported problem, or the torn last line
    non_blank = sum(1 for line in data.split(b"\n") if line.strip())
    assert non_blank - len(rows) - len(problems) in (0, 1)


@FUZZ
@given(st.binary(max_size=300))
def test_json_bytes_parse_or_value_error(data):
    try:
        parse_json_bytes(data)
    except ValueError as exc:
        assert str(exc)


@FUZZ
@given(st.one_of(st.binary(max_size=300),
                 st.lists(st.lists(st.text(max_size=8), max_size=4), max_size=6).map(
                     lambda rows: "\n".join(",".join(r) for r in rows).encode())))
def test_csv_loads_or_names_the_file(data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "data.csv"
        path.write_bytes(data)
        try:
            load_table(path)
        except DataFileError as exc:
            assert str(path) in str(exc)


@FUZZ
@given(st.binary(max_size=300))
def test_rig_text_parses_or_names_file_and_key(data):
    text = data.decode("utf-8", errors="replace")
    try:
        parse_rig(text, "fuzz.toml", check_protocols=False)
    except RigFileError as exc:
        assert str(exc).startswith("fuzz.toml:")


SET_KEYS = ["speeds_rpm", "up_down", "repeats", "record_s", "min_samples", "zero", "settle_timeout_s"]
SET_TEXT = st.one_of(
    st.text(alphabet="0123456789.:,;-+eEnaifINF ", max_size=30),
    st.sampled_from(["nan", "inf", "-inf", "1e308", "1e999", "0:1e9:1", "9" * 30, "true", "each", ""]),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(SET_KEYS), SET_TEXT)
def test_any_set_value_is_a_plan_or_one_line(capsys, key, text):
    from labkit.cli import main

    from .conftest import FIG525

    code = main(["run", str(FIG525), "speed-sweep", "--set", f"{key}={text}", "--dry-run"])
    out, err = capsys.readouterr()
    assert code in (0, 2)
    if code == 2:
        assert err.count("\n") == 1 and err.startswith("labkit run: "), err
    else:
        assert "all targets within the rig's limits" in out
