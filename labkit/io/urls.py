"""Pure parsing of labkit's transport URLs (no I/O): ``record://``, ``replay://``.

(``sim://`` belongs to the emulators: :mod:`labkit.emulators.urls`.)

* ``record://<inner-url>?cassette=PATH&port=NAME`` - ``cassette`` and ``port`` are taken out
  of the query; every other query key stays with the inner URL, so
  ``record://sim://mtsics?seed=3&cassette=rec/b.jsonl&port=balance`` records
  ``sim://mtsics?seed=3``. A real device: ``record:///dev/ttyUSB0?cassette=rec/b.jsonl``.
* ``replay://<cassette-path>?mode=strict|timed|faithful`` (relative paths are relative to the
  working directory; ``replay:///abs/path.jsonl`` for absolute ones). ``faithful`` takes
  ``stream=1`` (a device that talks unasked), ``setpoints=1`` (a motor controller: a write
  may match a recorded one of the same command with another value) and ``window=SECONDS``.
"""

from __future__ import annotations

from dataclasses import dataclass
from urllib.parse import parse_qsl, quote, unquote

from labkit.errors import PortURLError

RECORD_KEYS = ("cassette", "port")
REPLAY_MODES = ("strict", "timed", "faithful")
#: ``replay://`` options of ``mode=faithful`` (labkit.io.faithful_port)
FAITHFUL_FLAGS = ("stream", "setpoints")


def split_scheme(url: str) -> tuple[str, str]:
    """``"sim://mtsics?x=1"`` -> ``("sim", "mtsics?x=1")``; no scheme -> ``("", url)``."""
    scheme, sep, rest = url.partition("://")
    if not sep:
        return "", url
    return scheme.lower(), rest


def split_query(rest: str) -> tuple[str, list[tuple[str, str]]]:
    """``"mtsics?seed=3&x="`` -> ``("mtsics", [("seed", "3"), ("x", "")])``."""
    path, _, query = rest.partition("?")
    return path, parse_qsl(query, keep_blank_values=True)


@dataclass(frozen=True)
class RecordSpec:
    """What a ``record://`` URL asks for: the inner URL, the cassette path and the port name."""

    inner_url: str
    cassette: str
    port: str


def parse_record_url(url: str) -> RecordSpec:
    """Split ``record://<inner>?cassette=..&port=..`` (other query keys stay with the inner URL)."""
    scheme, rest = split_scheme(url)
    if scheme != "record":
        raise PortURLError(url, "expected a record://<inner-url>?cassette=PATH URL")
    inner, query = split_query(rest)
    own = {k: v for k, v in query if k in RECORD_KEYS}
    kept = [(k, v) for k, v in query if k not in RECORD_KEYS]
    if not inner:
        raise PortURLError(url, "no inner port URL after record://")
    if not own.get("cassette"):
        raise PortURLError(url, "record:// needs ?cassette=PATH (one cassette file per port)")
    if kept:
        inner += "?" + "&".join(f"{quote(k, safe='')}={quote(v, safe=':,/.;-_')}" for k, v in kept)
    cassette = own["cassette"]
    port = own.get("port") or _stem(cassette)
    return RecordSpec(inner, cassette, port)


def _stem(path: str) -> str:
    name = path.replace("\\", "/").rsplit("/", 1)[-1]
    return name.split(".", 1)[0] or "port"


@dataclass(frozen=True)
class ReplaySpec:
    """What a ``replay://`` URL asks for."""

    cassette: str
    mode: str = "strict"
    stream: bool = False
    setpoints: bool = False
    window: float | None = None


def parse_replay_url(url: str) -> ReplaySpec:
    """Parse ``replay://<cassette-path>?mode=strict|timed``."""
    scheme, rest = split_scheme(url)
    if scheme != "replay":
        raise PortURLError(url, "expected a replay://<cassette-path>?mode=strict|timed URL")
    path, query = split_query(rest)
    path = unquote(path)
    if not path:
        raise PortURLError(url, "no cassette path after replay://")
    mode = "strict"
    flags: dict[str, bool] = {}
    window = None
    for key, value in query:
        if key == "mode":
            if value not in REPLAY_MODES:
                raise PortURLError(url, f"mode={value!r}; choose one of {', '.join(REPLAY_MODES)}")
            mode = value
        elif key in FAITHFUL_FLAGS:
            if value not in ("0", "1"):
                raise PortURLError(url, f"{key}={value!r}; expected 0 or 1")
            flags[key] = value == "1"
        elif key == "window":
            window = _positive_seconds(url, key, value)
        else:
            raise PortURLError(url, f"unknown replay option {key!r} (mode=strict|timed|faithful; "
                                    f"with faithful: stream, setpoints, window)")
    if (flags or window is not None) and mode != "faithful":
        raise PortURLError(url, "stream, setpoints and window belong to mode=faithful")
    return ReplaySpec(path, mode, flags.get("stream", False), flags.get("setpoints", False), window)


def _positive_seconds(url: str, key: str, value: str) -> float:
    try:
        seconds = float(value)
    except ValueError:
        seconds = float("nan")
    if not seconds > 0 or seconds == float("inf"):
        raise PortURLError(url, f"{key}={value!r}; expected a positive number of seconds")
    return seconds
