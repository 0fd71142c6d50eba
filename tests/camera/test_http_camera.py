"""The camera's HTTP MJPEG path through the real OpenCV client, on a loopback server."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from labkit.devices.camera import open_camera
from labkit.errors import DeviceTimeout
from labkit.io.clock import RealClock

from .loopback import LoopbackMjpeg


def test_burst_delivers_the_servers_jpeg_bytes_with_arrival_times():
    with LoopbackMjpeg(fps=30) as server:
        camera = open_camera(server.url + "?timeout_s=3", RealClock(), name="phone")
        try:
            frames = camera.burst(20)
            time.sleep(0.4)  # the grab thread keeps draining: those frames are discarded, not queued
            newest = camera.latest()
            discarded = camera.discarded
        finally:
            camera.close()
        sent = set(server.frames)
    assert camera.settings.size == (320, 240) and camera.settings.fourcc == "MJPG"
    assert camera.settings.fps is None  # a network stream's own rate is invented: not reported
    assert all(f.payload in sent for f in frames)  # the camera's own bytes, no re-encoding
    assert len({f.payload for f in frames}) == 20
    assert [f.trusted for f in frames] == ["host"] * 20
    times = [f.t for f in frames]
    assert all(b > a for a, b in zip(times, times[1:], strict=False))
    rate = (len(frames) - 1) / (times[-1] - times[0])
    assert 15 < rate < 45, rate  # served at 30 fps (loaded 2-core CI machines: wide band)
    assert frames[0].image().shape == (240, 320, 3)
    assert newest is not None and newest.seq > frames[-1].seq and discarded >= 3


def test_drops_of_a_stream_are_counted_from_arrival_gaps_only_against_a_declared_rate():
    """The server leaves out frames 30-32 (their time passes): with ``nominal_fps=30`` the frame
    after the gap says 3 were lost; without it the stream's drops are not counted (0)."""
    from .loopback import numbered_jpeg

    for query, expected in (("?timeout_s=3&nominal_fps=30", 3), ("?timeout_s=3", 0)):
        with LoopbackMjpeg(fps=30, skip=frozenset({30, 31, 32})) as server:
            camera = open_camera(server.url + query, RealClock(), name="phone")
            try:
                frames = camera.burst(45)   # from about frame 5 (opening takes a moment)
            finally:
                camera.close()
        after = [f for f in frames if f.payload == numbered_jpeg(33)]
        assert len(after) == 1, query
        assert after[0].dropped_before == expected, (query, [f.dropped_before for f in frames])
        assert camera.settings.fps is None   # the declared rate is not what the camera accepted
        assert camera.settings.requested.get("nominal_fps") == (30.0 if expected else None)


def test_a_stream_that_stops_mid_burst_ends_with_one_line_within_the_timeout():
    with LoopbackMjpeg(fps=30, stall_after=8) as server:
        url = server.url + "?timeout_s=1"
        camera = open_camera(url, RealClock(), name="phone")
        start = time.monotonic()
        try:
            with pytest.raises(DeviceTimeout) as info:
                camera.burst(60)
        finally:
            elapsed = time.monotonic() - start
            camera.close()
    message = str(info.value)
    assert "\n" not in message
    assert "camera phone at " + url in message and "stopped sending frames" in message
    assert elapsed < 1.0 + 1.5, elapsed  # the documented timeout (timeout_s) plus scheduling slack


def test_probe_camera_prints_one_json_line_with_size_rate_and_timestamp_kind():
    with LoopbackMjpeg(fps=30) as server:
        env = {**os.environ, "OPENCV_LOG_LEVEL": "ERROR"}
        done = subprocess.run([sys.executable, "-m", "labkit", "probe", "camera", "--port", server.url,
                               "--frames", "15"], capture_output=True, text=True, timeout=60, env=env)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().splitlines()
    assert len(lines) == 1
    probe = json.loads(lines[0])
    assert probe["size"] == "320x240" and probe["format"] == "MJPG" and probe["timestamps"] == "host"
    assert 15 < probe["fps_measured"] < 45 and probe["frames"] == 15
    assert probe["dropped"] == 0 and probe["fps"] is None


def test_probe_of_a_silent_stream_exits_2_naming_the_camera():
    with LoopbackMjpeg(fps=30, stall_after=3) as server:
        url = server.url + "?timeout_s=1"
        done = subprocess.run([sys.executable, "-m", "labkit", "probe", "camera", "--port", url,
                               "--frames", "30"], capture_output=True, text=True, timeout=60,
                              env={**os.environ, "OPENCV_LOG_LEVEL": "ERROR"})
    assert done.returncode == 2
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("labkit probe: camera camera at " + url) and "stopped sending frames" in last
