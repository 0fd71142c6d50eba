"""A real-clock frame cassette served faithfully (labkit.devices.camera.faithful): each frame at its
recorded arrival time on the replay's clock, bursts matched to the recording's by step and take.
The cassette is the shipped real-clock cone-sweep's (recordings/sessions/real-cone-sweep)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from labkit.devices.camera.device import open_camera
from labkit.errors import ReplayMismatch
from labkit.io.clock import VirtualClock

CASSETTE = (Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "real-cone-sweep"
            / "cassettes" / "camera.jsonl")
URL = f"replay://{CASSETTE}?mode=faithful"


def _entries() -> list[dict]:
    return [json.loads(line) for line in CASSETTE.read_text().splitlines()[1:]]


def _bursts() -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    for e in _entries():
        out.setdefault(e["step"], []).append(e)
    return out


def test_frames_arrive_at_their_recorded_times_on_the_replay_clock():
    first = _bursts()["0.0"]
    clock = VirtualClock(first[0]["t_host"] - 5.0)  # the replayed run reached the burst 5 s early
    camera = open_camera(URL, clock)
    frames = camera.burst(len(first), step="0.0")
    assert [(f.t_host, f.t_device) for f in frames] == [(e["t_host"], e["t_device"]) for e in first]
    assert clock.now() == pytest.approx(first[-1]["t_host"], abs=1e-9)  # it waited for the camera
    assert camera.source.report()["served_late"] == 0
    data = CASSETTE.with_suffix(".mjpeg").read_bytes()
    assert frames[3].payload == data[first[3]["offset"]:first[3]["offset"] + first[3]["length"]]


def test_a_burst_asked_after_its_recorded_time_is_served_at_once_and_counted():
    first = _bursts()["0.0"]
    late = first[-1]["t_host"] + 0.25
    clock = VirtualClock(late)
    camera = open_camera(URL, clock)
    camera.burst(len(first), step="0.0")
    assert clock.now() == late
    report = camera.source.report()
    assert report["served_late"] == len(first)
    assert report["latest_s"] == pytest.approx(late - first[0]["t_host"], abs=1e-6)


def test_a_burst_the_recording_did_not_take_next_is_named_by_step_and_take():
    bursts = _bursts()
    clock = VirtualClock(bursts["0.0"][0]["t_host"])
    camera = open_camera(URL, clock)
    camera.burst(len(bursts["0.0"]), step="0.0")
    with pytest.raises(ReplayMismatch) as err:
        camera.burst(len(bursts["1.0"]), step="0.1")  # a retake the recording did not make
    text = str(err.value)
    assert "took a burst of 10 frames at step 0 (take 1)" in text
    assert "the recording's next burst was 10 frames at step 1 (take 0)" in text
    assert f"line {len(bursts['0.0']) + 2}" in text


def test_a_longer_burst_than_recorded_is_a_mismatch_not_a_burst_of_the_next_step():
    bursts = _bursts()
    camera = open_camera(URL, VirtualClock(bursts["0.0"][0]["t_host"]))
    with pytest.raises(ReplayMismatch, match="burst of 30 frames at step 0 .take 0.*was 10 frames"):
        camera.burst(30, step="0.0")
