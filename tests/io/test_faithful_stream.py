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

MOTOR = Path(__file__).resolve().parents[2] / "recordings/sessions/real-speed-sweep/cassettes/rotor_motor.jsonl"


def recorded_writes(path: Path) -> tuple[float, list[tuple[float, bytes]]]:
    reader = CassetteReader(path)
    origin = float(reader.header["clock_origin"])
    return origin, [(origin + e["t"], e["bytes"]) for e in reader if e["dir"] == "tx"]


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
