"""The parts of a faithful replay (docs/replay.md): its URL options, the clock that runs jobs when
the recording ran them, the recorded ticks and stalls, and a real-clock recording of a balance
served back at its recorded times with its polls matched by content."""

from __future__ import annotations

import json

import pytest

import labkit.emulators  # noqa: F401 - registers sim://
from labkit.devices.base import driver_class
from labkit.errors import PortURLError
from labkit.io.clock import STALL_JOB, RealClock, record_ticks, recorded_ticks
from labkit.io.ports import open_port
from labkit.io.replay_clock import ReplayClock
from labkit.io.urls import parse_replay_url


def test_faithful_url_options():
    spec = parse_replay_url("replay:///a/b.jsonl?mode=faithful&stream=1&window=0.2")
    assert (spec.mode, spec.stream, spec.setpoints, spec.window) == ("faithful", True, False, 0.2)
    for bad in ("replay://b.jsonl?mode=strict&stream=1", "replay://b.jsonl?mode=faithful&stream=yes",
                "replay://b.jsonl?mode=faithful&window=-1", "replay://b.jsonl?mode=faithful&window=inf"):
        with pytest.raises(PortURLError):
            parse_replay_url(bad)


def test_a_scheduled_job_runs_at_its_recorded_times_then_every_period():
    clock = ReplayClock(10.0, {"loop": [10.013, 10.071, 10.2]})
    seen: list[float] = []
    clock.every(0.05, seen.append, name="loop")
    clock.sleep(0.42)
    assert seen[:3] == [10.013, 10.071, 10.2]
    assert seen[3:] == pytest.approx([10.25, 10.3, 10.35, 10.4])


def test_a_wait_inside_a_job_takes_none_of_the_callers_time():
    clock = ReplayClock(0.0)
    inside: list[float] = []

    def job(t: float) -> None:
        clock.sleep(0.03)  # a status query waiting for its reply
        inside.append(clock.now())

    clock.every(0.05, job, name="loop")
    clock.sleep(0.1)
    assert clock.now() == pytest.approx(0.1)
    assert inside == pytest.approx([0.08, 0.13])


def test_a_recorded_stall_of_the_protocol_thread_is_replayed():
    clock = ReplayClock(5.0, {STALL_JOB: [5.05], STALL_JOB + "-woke": [5.9]})
    clock.sleep(0.05)
    assert clock.now() == pytest.approx(5.9)
    clock.sleep(0.05)
    assert clock.now() == pytest.approx(5.95)


def test_ticks_and_stalls_are_recorded_on_the_real_clock(tmp_path):
    clock = RealClock()
    recorder = record_ticks(clock, tmp_path)
    assert recorder is not None
    job = clock.every(0.01, lambda t: None, name="speed-control")
    clock.every(0.01, lambda t: None, name="balance-reader").cancel()
    import time

    time.sleep(0.1)
    job.cancel()
    recorder.close()
    ticks = recorded_ticks(tmp_path)
    assert len(ticks["speed-control"]) >= 3 and "balance-reader" not in ticks
    assert clock.on_run is None
    lines = [json.loads(line) for line in (tmp_path / "clock.jsonl").read_text().splitlines()]
    assert all(row["job"] == "speed-control" for row in lines)


def test_a_real_clock_balance_recording_serves_its_readings_with_other_poll_counts(tmp_path):
    """Record six polls of an emulated balance on the real clock, then replay faithfully on a
    ReplayClock: the same readings come back at the recorded pace, and a poll more than the
    recording held is answered from the recording, not refused."""
    cassette = tmp_path / "balance.jsonl"
    real = RealClock()
    port = open_port(f"record://sim://mtsics?seed=3&cassette={cassette}&port=balance", clock=real,
                     baudrate=9600, timeout=0.5)
    balance = driver_class("balance", "mtsics")(port, real, name="balance")
    recorded = [balance.read() for _ in range(6)]
    balance.close()
    header = json.loads(cassette.read_text().splitlines()[0])
    replay = ReplayClock(header["clock_origin"])
    port = open_port(f"replay://{cassette}?mode=faithful", clock=replay, baudrate=9600, timeout=0.5)
    balance = driver_class("balance", "mtsics")(port, replay, name="balance")
    replayed = [balance.read() for _ in range(7)]
    report = port.report()
    balance.close()
    assert [r.value for r in replayed[:6]] == [r.value for r in recorded]
    for mine, theirs in zip(replayed, recorded, strict=False):
        assert mine.t == pytest.approx(theirs.t, abs=0.01)
    assert report["identical"] == report["recorded_writes"]
