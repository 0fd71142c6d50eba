"""record:// tees a port into a cassette; replay:// serves it back byte-exact."""

from __future__ import annotations

import pytest
import serial

from labkit.devices.link import LineFramer
from labkit.devices.stream_reader import StreamReader
from labkit.emulators.base import DISCONNECT_MESSAGE
from labkit.errors import ReplayMismatch
from labkit.io.cassette import CassetteReader
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port


def echo_session(port: serial.SerialBase, words: list[str]) -> list[tuple[str, float]]:
    """A tiny 'driver': send each word, parse the echo into (word, clock time)."""
    readings = []
    assert port.read_until(b"\n") == b"READY\r\n"
    for word in words:
        port.write(word.encode() + b"\n")
        line = port.read_until(b"\n")
        assert line.startswith(b"ECHO ") and line.endswith(b"\r\n")
        readings.append((line[5:-2].decode(), port.clock.now()))
    return readings


def record(tmp_path, inner: str, name: str = "dev") -> str:
    cassette = tmp_path / f"{name}.jsonl"
    sep = "&" if "?" in inner else "?"
    return f"record://{inner}{sep}cassette={cassette}&port={name}", str(cassette)


def events(path: str) -> list[dict]:
    """The header and every event, each with all its keys (schema-2 lines leave some out)."""
    reader = CassetteReader(path)
    return [reader.header, *reader]


def test_cassette_holds_header_and_every_event_in_order(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo?latency=0.05", "balance")
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=0.5)
    echo_session(port, ["a"])
    assert port.read(4) == b""  # a timeout, recorded as a short read
    port.write(b"\x00\xff\n")
    port.close()
    header, *evs = events(cassette)
    assert header["format"] == "labkit-cassette" and header["schema"] == 2
    assert header["port"] == "balance" and header["url"] == "sim://test_echo?latency=0.05"
    assert header["serial"]["baudrate"] == 9600 and header["clock"] == "virtual"
    summary = [(e["dir"], e.get("event"), e.get("data")) for e in evs]
    assert summary == [
        ("ctl", "open", None),
        ("rx", None, "READY\r\n"),
        ("tx", None, "a\n"),
        ("rx", None, "ECHO a\r\n"),
        ("ctl", "short_read", None),
        ("tx", None, "AP8K"),  # base64 of 00 ff 0a
        ("ctl", "close", None),
    ]
    assert evs[5]["enc"] == "b64"
    assert evs[3]["t"] == pytest.approx(0.05)
    assert evs[4]["t"] == pytest.approx(0.55) and evs[4]["asked"] == 4 and evs[4]["got"] == 0
    assert all(e["port"] == "balance" for e in evs)


def test_record_keeps_the_inner_urls_own_query(tmp_path):
    cassette = tmp_path / "x.jsonl"
    port = open_port(f"record://sim://test_echo?latency=0.3&cassette={cassette}&seed=4",
                     clock=VirtualClock(), timeout=1.0)
    assert events(str(cassette))[0]["url"] == "sim://test_echo?latency=0.3&seed=4"
    assert events(str(cassette))[0]["port"] == "x"  # default port name: the cassette's stem
    port.read_until(b"\n")
    port.write(b"q\n")
    port.read_until(b"\n")
    assert port.clock.now() == pytest.approx(0.3)


def test_strict_replay_gives_identical_bytes_and_readings(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo?latency=0.05")
    rec_clock = VirtualClock()
    port = open_port(url, clock=rec_clock, timeout=1.0)
    recorded = echo_session(port, ["1.5", "2.25", "x y"])
    port.close()

    replay = open_port(f"replay://{cassette}", clock=VirtualClock(), timeout=1.0)
    replayed = echo_session(replay, ["1.5", "2.25", "x y"])
    replay.close()
    replay.assert_consumed()
    assert [w for w, _ in replayed] == [w for w, _ in recorded]


def test_timed_replay_reproduces_reading_times_on_a_virtual_clock(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo?latency=0.125")
    port = open_port(url, clock=VirtualClock(), timeout=1.0)
    recorded = echo_session(port, ["a", "b"])
    port.close()
    clock = VirtualClock()
    replay = open_port(f"replay://{cassette}?mode=timed", clock=clock, timeout=1.0)
    assert echo_session(replay, ["a", "b"]) == recorded == [("a", 0.125), ("b", 0.25)]
    replay.close()


def test_timed_replay_of_a_stream_delivers_frames_at_recorded_times_and_times_out(tmp_path):
    url, cassette = record(tmp_path, "sim://test_ticker?period=0.1")
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=1.0)
    frames: list[tuple[float, bytes]] = []
    reader = StreamReader(port, clock, LineFramer(), lambda t, f: frames.append((t, f)), period=0.01)
    reader.start()
    clock.advance(0.55)
    reader.stop()
    port.close()
    assert [f for _, f in frames] == [b"T 1", b"T 2", b"T 3", b"T 4", b"T 5"]

    clock2 = VirtualClock()
    replay = open_port(f"replay://{cassette}?mode=timed", clock=clock2, timeout=0.05)
    replayed: list[tuple[float, bytes]] = []
    reader2 = StreamReader(replay, clock2, LineFramer(), lambda t, f: replayed.append((t, f)),
                           period=0.01)
    reader2.start()
    clock2.advance(0.55)
    reader2.stop()
    assert [(round(t, 6), f) for t, f in replayed] == [(round(t, 6), f) for t, f in frames]
    replay.close()
    # a plain read with a timeout shorter than the gap returns nothing, then the frame
    # arrives exactly at its recorded time
    first_rx_t = next(e["t"] for e in events(cassette)[1:] if e["dir"] == "rx")
    again = open_port(f"replay://{cassette}?mode=timed", clock=VirtualClock(), timeout=0.05)
    empty_reads = 0
    while not (got := again.read(100)):
        empty_reads += 1
    assert empty_reads >= 1 and got == b"T 1\r\n"
    assert again.clock.now() == pytest.approx(first_rx_t)


def test_strict_mismatch_names_port_offset_expected_actual_with_caret(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo", "balance")
    port = open_port(url, clock=VirtualClock(), timeout=1.0)
    echo_session(port, ["SI", "S"])
    port.close()
    replay = open_port(f"replay://{cassette}", clock=VirtualClock(), timeout=1.0)
    replay.read_until(b"\n")
    replay.write(b"SI\n")
    replay.read_until(b"\n")
    with pytest.raises(ReplayMismatch) as caught:
        replay.write(b"Z\n")
    message = str(caught.value)
    assert "'balance'" in message and "byte 3 " in message
    lines = message.splitlines()
    expected_line = next(x for x in lines if x.strip().startswith("expected:"))
    actual_line = next(x for x in lines if x.strip().startswith("actual:"))
    caret = lines[-1].index("^")
    assert expected_line[caret] == "S" and actual_line[caret] == "Z"
    assert expected_line.endswith("S\\n") and actual_line.endswith("Z\\n")


def test_closing_with_unconsumed_events_fails_loudly(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo", "tach")
    port = open_port(url, clock=VirtualClock(), timeout=1.0)
    echo_session(port, ["a", "b"])
    port.close()
    replay = open_port(f"replay://{cassette}", clock=VirtualClock(), timeout=1.0)
    echo_session(replay, ["a"])
    with pytest.raises(ReplayMismatch, match=r"'tach'.*2 TX bytes never written"):
        replay.close()


def test_recorded_disconnect_replays_as_the_same_disconnect(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo?faults=disconnect_at:1")
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=5.0)
    assert port.read_until(b"\n") == b"READY\r\n"
    with pytest.raises(serial.SerialException):
        port.read(1)
    for retry in (lambda: port.in_waiting, lambda: port.write(b"again\n")):
        with pytest.raises(serial.SerialException):
            retry()  # a driver retrying on a dead port adds nothing to the cassette
    port.close()
    evs = events(cassette)[1:]
    errors = [e for e in evs if e.get("event") == "error"]
    assert len(errors) == 1 and errors[0]["message"] == DISCONNECT_MESSAGE
    assert [e.get("event") for e in evs[-2:]] == ["error", "close"]

    replay = open_port(f"replay://{cassette}?mode=timed", clock=VirtualClock(), timeout=5.0)
    assert replay.read_until(b"\n") == b"READY\r\n"
    with pytest.raises(serial.SerialException) as caught:
        replay.read(1)
    assert type(caught.value) is serial.SerialException
    assert str(caught.value) == DISCONNECT_MESSAGE
    assert replay.clock.now() == pytest.approx(1.0)
    with pytest.raises(serial.SerialException):
        replay.write(b"a\n")  # a dead port stays dead
    replay.close()
    replay.assert_consumed()


def test_recorded_write_error_is_raised_by_the_same_write(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo?faults=disconnect_at:1")
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=0.1)
    port.read_until(b"\n")
    port.write(b"a\n")
    clock.advance(2.0)
    with pytest.raises(serial.SerialException):
        port.write(b"b\n")
    port.close()
    replay = open_port(f"replay://{cassette}", clock=VirtualClock(), timeout=0.1)
    replay.read_until(b"\n")
    replay.write(b"a\n")
    with pytest.raises(serial.SerialException, match="device reports readiness"):
        replay.write(b"b\n")
    replay.close()


def test_replay_at_other_serial_settings_is_a_mismatch(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo")
    port = open_port(url, clock=VirtualClock(), timeout=0.1, baudrate=2400)
    port.close()
    with pytest.raises(ReplayMismatch, match="baudrate=9600 but the recording used baudrate=2400"):
        open_port(f"replay://{cassette}", clock=VirtualClock(), timeout=0.1)


def test_each_reopen_replays_the_next_recorded_session(tmp_path):
    url, cassette = record(tmp_path, "sim://test_echo?faults=disconnect_at:1,reconnect_after:1")
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=0.5)
    echo_session(port, ["first"])
    clock.advance(1.5)
    with pytest.raises(serial.SerialException):
        port.write(b"lost\n")
    port.close()
    clock.advance(1.0)
    port.open()  # replugged: a power-cycled device
    echo_session(port, ["second"])
    port.close()
    opens = [e for e in events(cassette)[1:] if e.get("event") == "open"]
    assert len(opens) == 2

    clock2 = VirtualClock()
    replay = open_port(f"replay://{cassette}?mode=timed", clock=clock2, timeout=0.5)
    echo_session(replay, ["first"])
    with pytest.raises(serial.SerialException):
        replay.write(b"lost\n")
    replay.close()
    with pytest.raises(ReplayMismatch, match="recorded 2 open"):
        replay.assert_consumed()  # the second session has not been replayed yet
    replay.open()
    assert echo_session(replay, ["second"])[0][0] == "second"
    replay.close()
    replay.assert_consumed()
    with pytest.raises(ReplayMismatch, match="opened 3 times"):
        replay.open()


def test_modem_lines_pass_through_record_to_the_real_port(tmp_path):
    url, _ = record(tmp_path, "loop://")
    port = open_port(url, timeout=0.1)
    port.rts = False
    assert port.cts is False  # loop:// reflects RTS on CTS
    port.rts = True
    assert port.cts is True
    port.write(b"ping")
    assert port.read(4) == b"ping"
    port.close()
