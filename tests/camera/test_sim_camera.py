"""The emulated camera (sim://camera) on a rig: the laser trace it films at the rotor's speed is
the model's cone angle, as `labkit analyse laser` reads it; frame cassettes replay byte for byte."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from labkit.devices.camera import open_camera
from labkit.devices.camera.avi import write_mjpeg_avi
from labkit.devices.camera.cassette import read_cassette, sidecar_path
from labkit.errors import CassetteError, DeviceError
from labkit.io.clock import VirtualClock
from labkit.rig import load_rig, open_rig


def spin_up(opened, clock, duty: float) -> None:
    motor = opened.drivers["rotor_motor"]
    motor.enable()
    motor.set_duty(duty)
    clock.sleep(4.0)  # the model motor's tau is 0.4 s


def test_sim_camera_films_the_models_cone_angle(tmp_path):
    rig = load_rig("emulated-camera")
    clock = VirtualClock()
    with open_rig(rig, clock) as opened:
        spin_up(opened, clock, 0.3)
        camera = opened.camera("camera")
        frames = camera.burst(30, step=0)
        truth = camera.source.truth(frames[0].t)
        truth_end = camera.source.truth(frames[-1].t)
    assert [f.seq for f in frames] == list(range(frames[0].seq, frames[0].seq + 30))
    assert all(f.trusted == "device" for f in frames) and camera.dropped == 0
    assert frames[1].t - frames[0].t == pytest.approx(1 / 30, abs=1e-9)  # on the run's clock
    assert truth["phi_rad"] == pytest.approx(truth_end["phi_rad"], rel=0.01)  # settled speed
    assert 3000 < truth["omega_rad_s"] * 30 / math.pi < 12000
    video = write_mjpeg_avi(tmp_path / "burst.avi", [f.payload for f in frames], 30.0, (320, 240))
    done = subprocess.run([sys.executable, "-m", "labkit", "analyse", "laser", str(video), "--json", "-",
                           "--screen-distance-mm", "500", "--mm-per-px", "2"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    tilt = result["tilt_rad"]
    measured = 0.5 * (tilt["major"] + tilt["minor"])
    assert result["quality"]["verdict"] == "ok"
    assert measured == pytest.approx(truth["phi_rad"], rel=0.05)


def test_record_then_replay_serves_identical_bytes_and_times(tmp_path):
    rig = load_rig("emulated-camera")
    clock = VirtualClock()
    with open_rig(rig, clock, record_to=tmp_path / "cassettes") as opened:
        spin_up(opened, clock, 0.25)
        camera = opened.camera("camera")
        recorded = camera.burst(6, step=0) + camera.burst(4, step=1)
    index = tmp_path / "cassettes" / "camera.jsonl"
    header, entries, data = read_cassette(index)
    assert header["settings"]["size"] == "320x240" and header["settings"]["fourcc"] == "MJPG"
    assert [e["step"] for e in entries] == [0] * 6 + [1] * 4
    assert len(data) == sum(len(f.payload) for f in recorded)
    assert len(data) / len(recorded) < 12_000  # compact: the stored JPEGs, no container

    def replay_camera(dev):
        return f"replay://{index}?mode=timed" if dev.kind == "camera" else dev.port

    with open_rig(rig, VirtualClock(), port_override=replay_camera) as opened:
        camera = opened.camera("camera")
        replayed = camera.burst(6) + camera.burst(4)
        with pytest.raises(DeviceError, match="has no more frames"):
            camera.burst(1)
    assert [f.payload for f in replayed] == [f.payload for f in recorded]
    assert [(f.seq, f.t, f.trusted) for f in replayed] == [(f.seq, f.t, f.trusted) for f in recorded]


def test_a_truncated_frame_sidecar_names_file_line_and_problem(tmp_path):
    clock = VirtualClock()
    index = tmp_path / "camera.jsonl"
    camera = open_camera(f"record://sim://camera?seed=2&cassette={index}", clock)
    camera.burst(3)
    camera.close()
    data = sidecar_path(index)
    data.write_bytes(data.read_bytes()[:-10])
    with pytest.raises(CassetteError, match=r"camera.jsonl:4: frame bytes .* truncated sidecar"):
        open_camera(f"replay://{index}", VirtualClock())


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(index=st.text(max_size=300), data=st.binary(max_size=64))
def test_any_frame_cassette_reads_or_is_a_cassette_error(tmp_path, index, data):
    path = tmp_path / "camera.jsonl"
    path.write_text(index, encoding="utf-8")
    sidecar_path(path).write_bytes(data)
    try:
        header, entries, stored = read_cassette(path)
    except CassetteError as exc:
        assert str(path) in str(exc)
        return
    camera = open_camera(f"replay://{path}", VirtualClock())
    for _ in entries:
        frame = camera.burst(1)[0]
        assert frame.payload in stored


def test_frame_cassette_header_lines_are_checked(tmp_path):
    path = tmp_path / "camera.jsonl"
    sidecar_path(path).write_bytes(b"")
    path.write_text(json.dumps({"format": "labkit-frames", "settings": {"size": "0x3"}}) + "\n")
    with pytest.raises(CassetteError, match="camera.jsonl:1: frame cassette header without usable settings"):
        read_cassette(path)
    path.write_text(json.dumps({"format": "labkit-frames", "settings": {"size": "4x3"}}) + "\n"
                    + json.dumps({"offset": 0, "length": 0}) + "\n")
    with pytest.raises(CassetteError, match="camera.jsonl:2: frame entry without"):
        read_cassette(path)


def test_a_reader_that_falls_behind_sees_drops_and_idle_slots_are_discarded():
    clock = VirtualClock()
    camera = open_camera("sim://camera?seed=3&fps=30", clock)
    first = camera.burst(3)
    clock.sleep(0.2)  # six frame slots pass while no burst is taken
    second = camera.burst(2)
    assert [f.dropped_before for f in first + second] == [0] * 5
    assert camera.discarded == second[0].seq - first[-1].seq - 1 >= 5 and camera.dropped == 0
    clock.every(1 / 60, lambda t: clock.sleep(0.1))  # a busy loop (jobs do not run jobs): falls behind
    third = camera.burst(3)
    assert camera.dropped > 0 and sum(f.dropped_before for f in third) == camera.dropped
    assert all(b.seq - a.seq - 1 == b.dropped_before for a, b in zip(third, third[1:], strict=False))
