"""Cassette tampering that keeps the protocol's bytes (issue 27): lines moved or swapped with
their times, a negative time (the cassette's time line, named with file and line), and any
change of a session that recorded its digests (data swapped between chunks, times kept)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from labkit.cli import main

REPO = Path(__file__).resolve().parents[2]
SESSIONS = REPO / "recordings" / "sessions"


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines()


def _write(path: Path, lines: list[str]) -> None:
    path.write_text("\n".join(lines) + "\n")


def _rx(lines: list[str]) -> list[int]:
    """The lines that are received chunks written in full (a schema-2 cassette's repeat lines,
    ``{"t": T, "r": K}``, name an earlier line instead and carry no ``dir``)."""
    return [i for i, line in enumerate(lines) if i and json.loads(line).get("dir") == "rx"]


def _swap_rx(lines: list[str]) -> None:
    """Two received chunks of a reply swapped, each with its time."""
    i = _rx(lines)[len(_rx(lines)) // 2]
    j = next(k for k in _rx(lines) if k > i and json.loads(lines[k])["t"] > json.loads(lines[i])["t"])
    lines[i], lines[j] = lines[j], lines[i]


def _negative(lines: list[str]) -> None:
    i = _rx(lines)[5]
    lines[i] = json.dumps({**json.loads(lines[i]), "t": -1.0})


def _move_tx(lines: list[str]) -> None:
    """A command moved three lines on (after its reply)."""
    tx = [i for i, line in enumerate(lines) if i and json.loads(line)["dir"] == "tx"]
    i = tx[len(tx) // 2]
    lines.insert(i + 3, lines.pop(i))


@pytest.mark.parametrize("tamper, words", [(_swap_rx, "goes back from"), (_negative, "negative time"),
                                           (_move_tx, "goes back from")])
def test_a_cassette_line_out_of_time_is_named(tmp_path, capsys, tamper, words):
    session = tmp_path / "s"
    shutil.copytree(SESSIONS / "speed-sweep-clean", session)
    cassette = session / "cassettes" / "balance.jsonl"
    lines = _lines(cassette)
    tamper(lines)
    _write(cassette, lines)
    assert main(["replay", str(session)]) == 1
    err = capsys.readouterr().err
    assert f"{cassette}:" in err and words in err, err


def test_a_session_with_digests_names_data_swapped_between_chunks(tmp_path, capsys):
    rig = str(REPO / "rigs" / "emulated-fig525.toml")
    assert main(["run", rig, "speed-sweep", "--sessions", str(tmp_path), "--set", "speeds_rpm=6000:8000:2000",
                 "--set", "record_s=0.5", "--no-progress"]) == 0
    (session,) = tmp_path.iterdir()
    digests = json.loads((session / "run.json").read_text())["digests"]
    assert {"events.jsonl", "cassettes/balance.jsonl", "readings/balance.jsonl"} <= set(digests)
    assert main(["replay", str(session)]) == 0, capsys.readouterr().err
    cassette = session / "cassettes" / "rotor_motor.jsonl"
    lines = _lines(cassette)
    j = _rx(lines)[0]
    i = next(k for k in _rx(lines) if json.loads(lines[k])["data"] != json.loads(lines[j])["data"])
    a, b = json.loads(lines[i]), json.loads(lines[j])
    lines[i], lines[j] = json.dumps({**a, "data": b["data"]}), json.dumps({**b, "data": a["data"]})
    _write(cassette, lines)
    assert main(["replay", str(session)]) == 1
    err = capsys.readouterr().err
    assert f"{cassette}: changed after the session ended" in err, err


def test_repeat_lines_of_two_threads_a_moment_apart_are_no_tampering(tmp_path):
    """A schema-2 repeat line ({"t": T, "r": K}) belongs to the thread of the event it repeats: a
    keep-alive's repeat and the control loop's repeated reply written 0.1 ms out of order (as a
    real-clock recording did) are two threads, not a line moved; the same within one thread is."""
    from labkit.session.integrity import timeline_problems

    header = {"format": "labkit-cassette", "schema": 2, "port": "m"}
    keepalive = {"t": 1.0, "dir": "tx", "data": "hRsQ", "enc": "b64", "th": "keepalive"}
    reply = {"t": 1.001, "dir": "rx", "data": "GwI=", "enc": "b64", "th": "speed-control"}
    cassette = tmp_path / "m.jsonl"
    # the keep-alive again (r 2) at 2.0005, then the reply again (r 2, now the older one) at 2.0004
    lines = [header, keepalive, reply, {"t": 2.0005, "r": 2}, {"t": 2.0004, "r": 2}]
    cassette.write_text("".join(json.dumps(line) + "\n" for line in lines))
    assert timeline_problems(cassette) == []
    same = [header, keepalive, reply, {"t": 2.0005, "r": 2}, {"t": 2.0004, "r": 1}]  # the keep-alive twice
    cassette.write_text("".join(json.dumps(line) + "\n" for line in same))
    assert any("goes back from 2.0005 (line 4, the same thread)" in p for p in timeline_problems(cassette))


def test_repeat_lines_of_a_compact_cassette_are_checked_in_their_own_thread(tmp_path):
    # schema 2 writes an event seen recently as {"t": T, "r": K}: its thread is the repeated
    # event's, so a keep-alive's repeat a little after the control thread's line is no time going
    # back (it was named "the same thread" in a loaded real-clock recording), a control repeat
    # going back from the control thread's own last line is
    from labkit.session.integrity import timeline_problems

    cassette = tmp_path / "m.jsonl"
    _write(cassette, [json.dumps({"format": "labkit-cassette", "schema": 2, "port": "m"}),
                      '{"t":1.0,"dir":"ctl","event":"reset_input_buffer","th":"control"}',
                      '{"t":1.05,"dir":"tx","data":"x","th":"keepalive"}',
                      '{"t":1.1,"r":1}',
                      '{"t":1.08,"r":2}',
                      '{"t":1.07,"r":1}'])
    problems = timeline_problems(cassette)
    assert len(problems) == 1, problems
    assert f"{cassette}:6: time 1.07 goes back from 1.08 (line 5, the same thread)" in problems[0]
