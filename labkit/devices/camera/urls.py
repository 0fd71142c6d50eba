"""Pure parsing of camera URLs (no I/O): which frame source, with which requested settings.

* ``/dev/videoN`` or ``v4l2:///dev/videoN?size=640x480&fps=60&fourcc=MJPG&exposure_s=0.002`` -
  a UVC camera through OpenCV's V4L2 backend;
* ``http://HOST:PORT/PATH`` (``https://`` too) - an MJPEG stream (phones, IP cameras);
  ``nominal_fps=30`` declares the rate set in the phone's app (drops are then counted from
  gaps in the arrival times; without it a stream's drops are not counted);
* ``sim://camera?seed=N&plant=NAME&size=320x240&fps=30&exposure_s=0.004`` - the emulated camera;
* ``record://<inner>?cassette=PATH&port=ROLE`` and ``replay://<cassette>?mode=strict|timed``:
  frame cassettes (:mod:`labkit.devices.camera.cassette`).

Settings a URL may ask for (:data:`SETTING_KEYS`); anything else is a :class:`PortURLError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from urllib.parse import parse_qsl

from labkit.errors import PortURLError
from labkit.io.urls import split_query, split_scheme

SETTING_KEYS = ("size", "fps", "fourcc", "exposure_s", "timeout_s")
SIM_KEYS = ("seed", "plant", "role", "screen_mm", "mm_per_px", "scene", "strobe", "body_mm", "ambient",
            "stop_after")
#: an MJPEG stream's keys besides timeout_s: the rate set in the phone's app, to count drops by
HTTP_KEYS = ("nominal_fps",)
MAX_SIDE_PX = 8192
MAX_FPS = 1000.0
#: a camera that sends nothing for this long ends the wait (``timeout_s`` in the URL changes it)
DEFAULT_TIMEOUT_S = 2.0


@dataclass(frozen=True)
class CameraRequest:
    """What a camera URL asks for: the source ``kind`` (``v4l2``, ``http``, ``sim``), its
    ``target`` (device path, stream URL or sim scene) and the settings asked for."""

    kind: str
    target: str
    size: tuple[int, int] | None = None
    fps: float | None = None
    fourcc: str | None = None
    exposure_s: float | None = None
    timeout_s: float = DEFAULT_TIMEOUT_S
    options: dict[str, str] = field(default_factory=dict)


def is_camera_url(url: str) -> bool:
    """True for URLs only a camera opens (``/dev/videoN``, ``v4l2://``, ``http(s)://``, ``sim://camera``)."""
    scheme, rest = split_scheme(url)
    if scheme in ("record", "replay"):
        return False
    if scheme == "":
        return url.startswith("/dev/video")
    sim_camera = scheme == "sim" and rest.split("?")[0].strip("/") == "camera"
    return scheme in ("v4l2", "http", "https") or sim_camera


def parse_size(url: str, text: str) -> tuple[int, int]:
    """``"640x480"`` -> ``(640, 480)``; PortURLError naming the URL otherwise."""
    w, sep, h = text.lower().partition("x")
    try:
        size = (int(w), int(h)) if sep else None
    except ValueError:
        size = None
    if size is None or not (0 < size[0] <= MAX_SIDE_PX and 0 < size[1] <= MAX_SIDE_PX):
        raise PortURLError(url, f"size={text!r}: expected WIDTHxHEIGHT, e.g. 640x480 (at most {MAX_SIDE_PX})")
    return size


def _positive(url: str, key: str, text: str, cap: float) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value <= cap:
        raise PortURLError(url, f"{key}={text!r}: expected a number in (0, {cap:g}]")
    return value


def _settings(url: str, query: list[tuple[str, str]], allowed: tuple[str, ...]) -> dict:
    out: dict = {"options": {}}
    for key, value in query:
        if key == "size":
            out["size"] = parse_size(url, value)
        elif key == "fps":
            out["fps"] = _positive(url, key, value, MAX_FPS)
        elif key == "exposure_s":
            out["exposure_s"] = _positive(url, key, value, 10.0)
        elif key == "timeout_s":
            out["timeout_s"] = _positive(url, key, value, 600.0)
        elif key == "fourcc":
            if len(value) != 4 or not value.isascii():
                raise PortURLError(url, f"fourcc={value!r}: expected four characters, e.g. MJPG or YUYV")
            out["fourcc"] = value.upper()
        elif key in allowed:
            out["options"][key] = value
        else:
            raise PortURLError(url, f"unknown camera option {key!r}; known: "
                               f"{', '.join(SETTING_KEYS + allowed)}")
    return out


def parse_camera_url(url: str) -> CameraRequest:
    """Parse a live camera URL (not ``record://``/``replay://``: those wrap one)."""
    scheme, rest = split_scheme(url)
    if scheme == "" and url.startswith("/dev/video"):
        scheme, rest = "v4l2", url
    if scheme == "v4l2":
        path, query = split_query(rest)
        if not path.startswith("/dev/"):
            raise PortURLError(url, "expected v4l2:///dev/videoN?size=..&fps=..&fourcc=..&exposure_s=..")
        return CameraRequest("v4l2", path, **_settings(url, query, ()))
    if scheme in ("http", "https"):
        # the stream's own query (e.g. ?action=stream) stays with it; labkit's keys are taken out
        base, _, query_text = url.partition("?")
        query = parse_qsl(query_text, keep_blank_values=True)
        ours = SETTING_KEYS + HTTP_KEYS
        own = [(k, v) for k, v in query if k in ours]
        kept = "&".join(f"{k}={v}" for k, v in query if k not in ours)
        fixed = [k for k, _ in own if k not in ("timeout_s", *HTTP_KEYS)]
        if fixed:  # OpenCV cannot change a stream's settings: asking would be ignored silently
            raise PortURLError(url, f"{', '.join(fixed)}: an MJPEG stream's settings are set in the "
                                    "camera or its app (IP Webcam: Video preferences), not in the URL; "
                                    "only timeout_s and nominal_fps (the rate set in the app, to count "
                                    "drops by)")
        for key, value in own:
            if key == "nominal_fps":
                _positive(url, key, value, MAX_FPS)
        return CameraRequest("http", base + (f"?{kept}" if kept else ""), **_settings(url, own, HTTP_KEYS))
    if scheme == "sim":
        scene, query = split_query(rest)
        if scene.strip("/") != "camera":
            raise PortURLError(url, "a camera's sim:// URL is sim://camera?seed=..&plant=..")
        if any(k == "fourcc" for k, _ in query):
            raise PortURLError(url, "fourcc: the emulated camera always sends MJPEG (JPEG frames)")
        return CameraRequest("sim", "camera", **_settings(url, query, SIM_KEYS))
    raise PortURLError(url, "not a camera URL: use /dev/videoN, v4l2:///dev/videoN?..., "
                            "http://HOST:PORT/PATH, sim://camera?..., record://<camera-url>?cassette=.. "
                            "or replay://<cassette>")
