"""A faithful replay reads its cassette as the clock goes (labkit/io/faithful_sessions.py,
docs/decisions/0030-compact-cassettes.md): it holds the recorded writes of a few seconds
around the clock, not the whole recording, and still matches every write by content and
counts every recorded write in its report."""

from __future__ import annotations

from pathlib import Path

from labkit.io.cassette import CassetteReader
from labkit.io.faithful_port import SETPOINT_WINDOW_S
from labkit.io.faithful_sessions import FORGET_MARGIN_S, LOOKAHEAD_S
from labkit.io.ports import open_port
from labkit.io.replay_clock import ReplayClock

RECORDING = Path(__file__).resolve().parents[2] / "recordings/sessions/real-speed-sweep"
MOTOR = RECORDING / "cassettes" / "rotor_motor.jsonl"


def recorded_writes(path: Path) -> tuple[float, list[tuple[float, bytes]]]:
    reader = CassetteReader(path)
    origin = float(reader.header["clock_origin"])
    return origin, [(origin + e["t"], e["bytes"]) for e in reader if e["dir"] == "tx"]


def reopened(path: Path) -> float:
    """The cassette time of the port's second open."""
    return [e["t"] for e in CassetteReader(path) if e["dir"] == "ctl" and e.get("event") == "open"][1]


def most_in_any_span(times: list[float], span: float) -> int:
    """The most writes the recording made in any ``span`` seconds."""
    best, lo = 0, 0
    for hi, t in enumerate(times):
        while times[lo] < t - span:
            lo += 1
        best = max(best, hi - lo + 1)
    return best


def test_a_motor_recording_replays_holding_only_the_writes_around_the_clock():
    origin, writes = recorded_writes(MOTOR)
    clock = ReplayClock(origin)
    port = open_port(f"replay://{MOTOR}?mode=faithful&setpoints=1", clock=clock, baudrate=9600, timeout=0.2)
    held = []
    for t, data in writes:
        if t > clock.now():
            clock.sleep_until(t)
        port.write(data)
        held.append(port.holding()["writes"])
    report = port.report()
    port.close()
    assert report["identical"] == report["recorded_writes"] == len(writes)
    span = LOOKAHEAD_S + SETPOINT_WINDOW_S + FORGET_MARGIN_S
    # writes are forgotten in batches (at most 256 more than the window), so the bound is the
    # most writes in any span of the window and look-ahead, plus the batch
    bound = most_in_any_span([t for t, _ in writes], span + 1.0) + 256
    assert max(held) <= bound < len(writes)


def test_a_replay_that_stops_early_still_counts_every_recorded_write():
    origin, writes = recorded_writes(MOTOR)
    clock = ReplayClock(origin)
    port = open_port(f"replay://{MOTOR}?mode=faithful&setpoints=1", clock=clock, baudrate=9600, timeout=0.2)
    half = writes[: len(writes) // 2]
    for t, data in half:
        if t > clock.now():
            clock.sleep_until(t)
        port.write(data)
    report = port.report()  # reads the rest of the cassette: what was not sent again
    port.close()
    assert report["recorded_writes"] == len(writes)
    assert report["identical"] == len(half)
    assert report["not_repeated"] == len(writes) - len(half)


def test_the_report_counts_the_writes_of_sessions_the_replay_never_opened(tmp_path):
    """A balance recorded in two open/close sessions (and a third open), replayed through its
    first only: the report still counts the writes of the other two, read from the cassette."""
    import labkit.emulators  # noqa: F401 - registers sim://
    from labkit.devices.registry import driver_class
    from labkit.io.clock import RealClock

    cassette = tmp_path / "balance.jsonl"
    url = f"record://sim://mtsics?seed=3&cassette={cassette}&port=balance"
    real = RealClock()
    port = open_port(url, clock=real, baudrate=9600, timeout=0.5)
    balance = driver_class("balance", "mtsics")(port, real, name="balance")
    recorded = [balance.read() for _ in range(3)]
    for _ in range(2):
        port.close()
        port.open()
        balance.read()
    port.close()
    origin, writes = recorded_writes(cassette)
    clock = ReplayClock(origin)
    port = open_port(f"replay://{cassette}?mode=faithful", clock=clock, baudrate=9600, timeout=0.5)
    balance = driver_class("balance", "mtsics")(port, clock, name="balance")
    replayed = [balance.read() for _ in range(3)]
    report = port.report()
    port.close()
    assert [r.value for r in replayed] == [r.value for r in recorded]
    second_open = reopened(cassette)
    first_session = sum(1 for e in CassetteReader(cassette) if e["dir"] == "tx" and e["t"] < second_open)
    assert report["recorded_writes"] == len(writes)
    assert report["identical"] == first_session
    assert report["not_repeated"] == len(writes) - first_session >= 2
