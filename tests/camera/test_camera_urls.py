"""Camera URLs: parsed without I/O; every malformed one is a PortURLError naming it."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.devices.camera.urls import is_camera_url, parse_camera_url
from labkit.errors import PortURLError, RigFileError
from labkit.rig import parse_rig


def test_v4l2_url_with_settings():
    r = parse_camera_url("v4l2:///dev/video2?size=640x480&fps=60&fourcc=mjpg&exposure_s=0.002")
    assert (r.kind, r.target, r.size, r.fps, r.fourcc, r.exposure_s) == \
        ("v4l2", "/dev/video2", (640, 480), 60.0, "MJPG", 0.002)
    assert parse_camera_url("/dev/video0").target == "/dev/video0"


def test_http_url_keeps_the_streams_own_query():
    r = parse_camera_url("http://192.168.1.20:8080/video?action=stream&timeout_s=5")
    assert r.target == "http://192.168.1.20:8080/video?action=stream" and r.timeout_s == 5.0


@pytest.mark.parametrize("url, words", [
    ("v4l2:///dev/video0?size=640", "size='640'"),
    ("v4l2:///dev/video0?fps=-3", "fps='-3'"),
    ("v4l2:///dev/video0?fourcc=MJPEG", "four characters"),
    ("sim://camera?gain=3", "unknown camera option 'gain'"),
    ("sim://balance", "sim://camera"),
    ("ftp://x/y", "not a camera URL"),
    ("http://phone:8080/video?fps=30", "fps: an MJPEG stream's settings are set in the camera"),
    ("sim://camera?fourcc=YUYV", "always sends MJPEG"),
])
def test_bad_urls_name_the_problem(url, words):
    with pytest.raises(PortURLError) as info:
        parse_camera_url(url)
    assert url in str(info.value) and words in str(info.value)


@settings(max_examples=60, deadline=None)
@given(st.text(max_size=80))
def test_any_text_parses_or_is_a_port_url_error(text):
    for url in (text, "sim://camera?" + text, "v4l2:///dev/video0?" + text):
        try:
            parse_camera_url(url)
        except PortURLError:
            pass


def test_is_camera_url():
    assert is_camera_url("/dev/video0") and is_camera_url("http://h:1/v") and is_camera_url("sim://camera")
    assert not is_camera_url("/dev/ttyUSB0") and not is_camera_url("sim://mtsics")


def test_rig_file_checks_a_camera_url_at_its_key():
    text = """
[rig]
name = "t"
[devices.camera]
kind = "camera"
protocol = "frames"
port = "sim://camera?size=12"
[limits]
max_speed_rpm = 1000
max_ramp_rpm_per_s = 100
"""
    with pytest.raises(RigFileError, match=r"devices.camera.port: size='12'"):
        parse_rig(text, "t.toml")
