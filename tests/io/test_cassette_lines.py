"""Schema-2 cassette lines (docs/decisions/0030-compact-cassettes.md): every event read back as
written (bytes, times bit for bit, every key), repeats written short, schema-1 cassettes still
read, and a strict replay that holds only what it has read ahead."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.errors import CassetteError
from labkit.io.cassette import CassetteReader, CassetteWriter, load_cassette, make_header
from labkit.io.cassette_lines import RECENT
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port

ROOT = Path(__file__).resolve().parents[2]

#: events as RecordSerial makes them: (dir, data, fields)
EVENT = st.one_of(
    st.tuples(st.just("tx"), st.sampled_from([b"\x85\x00\x10", b"\xa1\x00", b"SI\r\n", b"\x00\xff"]),
              st.fixed_dictionaries({"call": st.sampled_from(["write", "SI", "read_stable"]),
                                     "th": st.sampled_from([None, "speed-control", "m-keepalive"])})),
    st.tuples(st.just("rx"), st.binary(min_size=1, max_size=6),
              st.fixed_dictionaries({"call": st.sampled_from(["read", "read_until", "SI"]),
                                     "th": st.sampled_from([None, "speed-control"])})),
    st.tuples(st.just("ctl"), st.none(),
              st.sampled_from([{"event": "reset_input_buffer", "call": "reset_input_buffer"},
                               {"event": "short_read", "asked": 4, "got": 0, "call": "read"},
                               {"event": "short_read", "asked": 4, "got": 0, "call": "SI"},
                               {"event": "close", "call": "close"},
                               {"event": "open", "serial": {"baudrate": 9600}},
                               {"event": "identity", "identity": {"model": "X"}}])),
)


def expected_event(t: float, direction: str, data: bytes | None, fields: dict) -> dict:
    """What a schema-1 cassette held for this event (CassetteReader's view, minus ``line``)."""
    from labkit.io.cassette import encode_data

    event = {"t": t, "port": "motor", "dir": direction}
    if data is not None:
        event.update(encode_data(data))
        event["bytes"] = data
    event.update({k: v for k, v in fields.items() if v is not None})
    return event


#: times, often equal to the one before (left out of the line), -0.0 kept apart from 0.0
TIME = st.one_of(st.sampled_from([0.0, -0.0, 0.05, 1e-9, 20.70600000000016]), st.floats(0, 1e6))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(TIME, EVENT), max_size=120))
def test_every_event_reads_back_as_written(tmp_path_factory, events):
    path = tmp_path_factory.mktemp("c") / "motor.jsonl"
    writer = CassetteWriter(path, make_header("motor", "sim://x", {}, clock="virtual", clock_origin=0.0))
    for t, (direction, data, fields) in events:
        writer.event(t, "motor", direction, data, **fields)
    writer.close()
    read = [{k: v for k, v in e.items() if k != "line"} for e in CassetteReader(path)]
    assert read == [expected_event(t, *event) for t, event in events]
    assert [repr(e["t"]) for e in read] == [repr(t) for t, _ in events]  # bit for bit, never rounded


def test_a_keep_alive_is_written_as_a_repeat_of_the_last_write(tmp_path):
    path = tmp_path / "motor.jsonl"
    writer = CassetteWriter(path, make_header("motor", "sim://x", {}))
    for i in range(40):  # control loop write, then the keep-alive resends it; a poll every 4th tick
        writer.event(0.05 * i, "motor", "tx", bytes([0x85, 0, i]), call="write")
        writer.event(0.05 * i + 0.001, "motor", "tx", bytes([0x85, 0, i]), call="write")
        if i % 4 == 0:
            writer.event(0.05 * i + 0.002, "motor", "tx", b"\xa1\x00", call="write", th="speed-control")
            writer.event(0.05 * i + 0.003, "motor", "rx", b"\x00\x00", call="read", th="speed-control")
    writer.close()
    lines = path.read_text().splitlines()[1:]
    assert lines[0] == '{"t":0.0,"dir":"tx","data":"hQAA","enc":"b64"}'
    repeats = [json.loads(line) for line in lines if '"r":' in line]
    assert all(set(r) == {"t", "r"} for r in repeats)
    # every keep-alive repeats the line before it; from the 2nd poll on the poll and its
    # unchanged reply repeat the ones 6 distinct events back (behind 4 setpoints)
    assert [r["r"] for r in repeats].count(1) == 40
    assert [r["r"] for r in repeats].count(6) == 9 * 2 and len(repeats) == 40 + 18
    events = list(CassetteReader(path))
    assert len(events) == 40 * 2 + 10 * 2
    assert events[-7]["bytes"] == b"\x00\x00" and events[-7]["th"] == "speed-control"
    assert events[-8]["t"] == 0.05 * 36 + 0.002 and events[-1]["bytes"] == bytes([0x85, 0, 39])


def test_a_repeat_of_nothing_is_named_with_its_line(tmp_path):
    path = tmp_path / "c.jsonl"
    header = {"format": "labkit-cassette", "schema": 2, "port": "p"}
    path.write_text(json.dumps(header) + "\n" + '{"t":0,"dir":"ctl","event":"open"}\n' + '{"t":1,"r":2}\n')
    with pytest.raises(CassetteError, match=r"c.jsonl:3: key 'r': 2 is not one of the 1 recent events"):
        load_cassette(path)
    assert RECENT >= 16  # a motor's poll cycle fits in the list


def test_schema_1_cassettes_still_read_and_an_unknown_schema_is_refused(tmp_path):
    old = ROOT / "recordings" / "cassettes" / "motor-pololu_smc.jsonl"
    reader = CassetteReader(old)
    assert reader.header["schema"] == 1
    events = list(reader)
    assert events and all(e["port"] == reader.port and "line" in e for e in events)
    bad = tmp_path / "c.jsonl"
    bad.write_text(json.dumps({"format": "labkit-cassette", "schema": 3, "port": "p"}) + "\n")
    with pytest.raises(CassetteError, match=r"c.jsonl:1: schema 3 is not supported"):
        CassetteReader(bad)


def test_a_strict_replay_reads_the_cassette_as_it_goes(tmp_path):
    """A long recording: the replay never holds more than the few events it read ahead."""
    cassette = tmp_path / "echo.jsonl"
    port = open_port(f"record://sim://test_echo?cassette={cassette}&port=echo", clock=VirtualClock(),
                     timeout=0.5)
    assert port.read_until(b"\n") == b"READY\r\n"
    for i in range(400):
        port.write(f"w{i}\n".encode())
        port.read_until(b"\n")
    port.close()
    replay = open_port(f"replay://{cassette}?mode=timed", clock=VirtualClock(), timeout=0.5)
    held = []
    assert replay.read_until(b"\n") == b"READY\r\n"
    for i in range(400):
        replay.write(f"w{i}\n".encode())
        assert replay.read_until(b"\n") == f"ECHO w{i}\r\n".encode()
        held.append(len(replay._session.device) + len(replay._session.tx_pending))
    replay.close()
    replay.assert_consumed()
    assert max(held) <= 2
