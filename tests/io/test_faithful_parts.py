"""The parts of a faithful replay (docs/explanation/replay.md): its URL options, the clock that runs jobs when
the recording ran them, the recorded ticks and stalls, and a real-clock recording of a balance
served back at its recorded times with its polls matched by content."""

from __future__ import annotations

import json
import sys

import pytest

import labkit.emulators  # noqa: F401 - registers sim://
from labkit.devices.registry import driver_class
from labkit.errors import PortURLError
from labkit.io.clock import (
    LATE_JOB,
    STALL_JOB,
    RealClock,
    read_site,
    record_ticks,
    recorded_runs,
    recorded_ticks,
)
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
    # the speed loop's ticks; a reader only where a run handed its lines over late (a loaded PC)
    assert all(row["job"] == "speed-control" or "done" in row for row in lines)


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
        assert mine.t == pytest.approx(theirs.t, abs=1e-6)  # read when the recording read it
    assert report["identical"] == report["recorded_writes"]


def test_a_recorded_stand_still_outside_a_sleep_is_repeated():
    """The recording's protocol thread read the clock at 5.4 after 5.1 (it waited for the control
    loop's lock): the replayed protocol reading the clock at 5.1 stands still until 5.4, with the
    jobs due meanwhile run; a later read is not held again."""
    clock = ReplayClock(5.0, runs={LATE_JOB: [(5.1, 5.4, "")]})
    ticks: list[float] = []
    clock.every(0.1, ticks.append, name="speed-control")
    clock.sleep(0.1)
    assert clock.now() == pytest.approx(5.4)
    assert ticks == pytest.approx([5.1, 5.2, 5.3, 5.4])
    clock.sleep(0.05)
    assert clock.now() == pytest.approx(5.45)
    assert clock.repeated["stood_still"] == 1


def _settle_check(clock: ReplayClock | None) -> float | str:
    """The protocol's settle check reading the clock (without a clock: the site of that read)."""
    return read_site(1) if clock is None else clock.now()


def test_a_stand_still_waits_for_the_read_where_the_recording_stood_still():
    """Reads between two sleeps all happen at one replayed time: the stand-still is taken at the
    read from the recorded site (the settle check), not at an earlier one (the step's event)."""
    site = _settle_check(None)
    assert site == "test_faithful_parts.py:_settle_check+2"   # its first frame: matched as a prefix
    clock = ReplayClock(5.0, runs={LATE_JOB: [(5.1, 5.4, site)]})
    clock.sleep(0.1)
    assert clock.now() == pytest.approx(5.1)   # another site: no stand-still
    assert _settle_check(clock) == pytest.approx(5.4)


def test_a_readers_late_delivery_is_seen_when_the_recording_saw_it():
    """A tachometer reader read at 0.2 but handed its lines over only at 0.35 (its thread lost
    the CPU): in the replay its job runs at 0.35 with the clock reading 0.2, so the speed loop
    ticking at 0.3 and the protocol at 0.3 do not see those lines yet, as in the recording."""
    clock = ReplayClock(0.0, {"tach-reader": [0.1, 0.2, 0.4]}, {"tach-reader": [(0.195, 0.35, "")]})
    delivered: list[tuple[float, float]] = []   # (the reader's clock, the caller's time)
    seen_by_loop: list[int] = []
    clock.every(0.005, lambda t: delivered.append((clock.now(), clock._now)), name="tach-reader")
    clock.every(0.3, lambda t: seen_by_loop.append(len(delivered)), name="speed-control")
    clock.sleep(0.3)
    assert len(delivered) == 1 and seen_by_loop == [1]
    clock.sleep(0.06)
    assert delivered[1] == pytest.approx((0.2, 0.35))
    naive = ReplayClock(0.0, {"tach-reader": [0.1, 0.2, 0.4]})
    count: list[float] = []
    naive.every(0.005, count.append, name="tach-reader")
    naive.sleep(0.3)
    assert len(count) == 2   # without the record the lines are there at 0.2


def test_stand_stills_and_late_deliveries_are_recorded_on_the_real_clock(tmp_path):
    import threading
    import time

    clock = RealClock()
    recorder = record_ticks(clock, tmp_path)
    assert recorder is not None
    clock.now()
    time.sleep(0.08)   # the protocol thread busy outside the clock (a lock, a blocking call)
    clock.now()
    slow = threading.Event()

    def reader(t: float) -> None:
        time.sleep(0.01)   # the reader's thread loses the CPU between its read and its delivery
        slow.set()

    job = clock.every(0.02, reader, name="tach-reader")
    slow.wait(2.0)
    time.sleep(0.05)
    job.cancel()
    recorder.close()
    runs = recorded_runs(tmp_path)
    (began, woke, site), = runs[LATE_JOB]
    assert woke - began >= 0.079   # at least the time it stood still
    assert site.startswith(f"test_faithful_parts.py:{sys._getframe().f_code.co_name}+")  # this function
    assert runs["tach-reader"] and all(end - start >= 0.01 for start, end, _ in runs["tach-reader"])
    assert LATE_JOB not in recorded_ticks(tmp_path) and "tach-reader" not in recorded_ticks(tmp_path)


def test_a_reader_run_a_tick_began_in_is_recorded_though_quick(tmp_path):
    """A loaded recording: the speed loop ticked 0.6 ms after the tachometer's read, and the
    reader handed its lines over 1 ms later: the tick saw the tachometer silent. Such a run is
    recorded (its lines are delivered after the tick in the replay); a quick run no tick began
    in is not."""
    clock = RealClock()
    recorder = record_ticks(clock, tmp_path)
    assert recorder is not None
    recorder("speed-control", 100.0)
    recorder.done("tach-reader", 100.01, 100.0105)    # quick, no tick in it
    recorder("speed-control", 100.0506)
    recorder.done("tach-reader", 100.05, 100.0511)    # quick, but the tick began in it
    recorder.close()
    assert recorded_runs(tmp_path)["tach-reader"] == [(100.05, 100.0511, "")]
