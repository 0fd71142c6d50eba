"""Cassette encoding and loading: lossless bytes, readable text, errors that name the line."""

from __future__ import annotations

import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from labkit.emulators.urls import parse_sim_url
from labkit.errors import CassetteError, PortURLError
from labkit.io.cassette import decode_data, encode_data, load_cassette
from labkit.io.urls import parse_record_url, parse_replay_url


@given(st.binary(max_size=200))
def test_any_bytes_survive_a_json_round_trip(data):
    event = json.loads(json.dumps(encode_data(data)))
    assert decode_data(event) == data


def test_printable_lines_stay_readable_and_binary_goes_base64():
    assert encode_data(b"S S      12.345 g\r\n") == {"data": "S S      12.345 g\r\n"}
    assert encode_data(b"\x02\x83\x01") == {"data": "AoMB", "enc": "b64"}


HEADER = {"format": "labkit-cassette", "schema": 1, "port": "p"}


def write_lines(tmp_path, *objs) -> str:
    path = tmp_path / "c.jsonl"
    path.write_text("\n".join(o if isinstance(o, str) else json.dumps(o) for o in objs) + "\n")
    return str(path)


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ("{not json", r"c.jsonl:2: not JSON"),
        ({"t": "x", "port": "p", "dir": "rx", "data": ""}, r"c.jsonl:2: key 't'"),
        ({"t": 0, "port": "p", "dir": "up", "data": ""}, r"c.jsonl:2: key 'dir': 'up'"),
        ({"t": 0, "port": "p", "dir": "ctl", "event": "boom"}, r"c.jsonl:2: key 'event': 'boom'"),
        ({"t": 0, "port": "p", "dir": "rx", "data": "!!", "enc": "b64"}, r"c.jsonl:2: .*base64"),
    ],
)
def test_bad_cassette_lines_name_file_line_and_key(tmp_path, line, problem):
    with pytest.raises(CassetteError, match=problem):
        load_cassette(write_lines(tmp_path, HEADER, line))


def test_wrong_header_and_missing_file_are_named(tmp_path):
    with pytest.raises(CassetteError, match=r"c.jsonl:1: format is 'other'"):
        load_cassette(write_lines(tmp_path, {"format": "other"}))
    with pytest.raises(CassetteError, match=r"nope.jsonl:0: cannot read cassette"):
        load_cassette(tmp_path / "nope.jsonl")


def test_port_urls_parse_into_their_parts():
    spec = parse_sim_url("sim://mtsics?seed=3&faults=garbage:0.1,overload&plant=fig525&role=balance&unit=g")
    assert (spec.protocol, spec.seed, spec.plant, spec.role) == ("mtsics", 3, "fig525", "balance")
    assert spec.faults == {"garbage": 0.1, "overload": 1.0} and spec.options == {"unit": "g"}
    rec = parse_record_url("record://sim://mtsics?seed=3&cassette=rec/balance.jsonl&port=balance")
    assert (rec.inner_url, rec.cassette, rec.port) == ("sim://mtsics?seed=3", "rec/balance.jsonl", "balance")
    assert parse_record_url("record:///dev/ttyUSB0?cassette=a/b.jsonl").inner_url == "/dev/ttyUSB0"
    assert parse_record_url("record://hwgrep://0403:6001&n=1?cassette=m.jsonl").inner_url == (
        "hwgrep://0403:6001&n=1")
    assert parse_replay_url("replay:///abs/x.jsonl?mode=timed").cassette == "/abs/x.jsonl"
    with pytest.raises(PortURLError, match="needs \\?cassette=PATH"):
        parse_record_url("record://sim://mtsics")
    with pytest.raises(PortURLError, match="mode='fast'"):
        parse_replay_url("replay://x.jsonl?mode=fast")
