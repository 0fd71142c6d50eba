"""Frame cassettes: what a camera delivered, stored as compactly as the serial cassettes.

* ``ROLE.jsonl`` - the index: a header line ``{"format": "labkit-frames", "version": 1, "url",
  "settings"}`` (the settings the camera *accepted*), then one line per frame handed to the run:
  ``seq``, ``t_host``, ``t_device``, ``trusted``, ``dropped_before``, ``length``, ``fmt``,
  ``offset`` (into the sidecar), ``step`` (the burst's label, e.g. the speed step) and ``meta``
  if the source adds any (the emulated camera: the model's cone angle at that frame); a burst
  the camera failed ends, after the frames it did send, in a fault line ``{"fault": "DeviceTimeout"
  or "DeviceError", "device", "reason", "step", "frames_asked", "t_host"}``;
* ``ROLE.mjpeg`` - the sidecar: the frames' bytes concatenated, exactly as the camera sent them
  when it sends JPEG (MJPEG webcams, phones, the emulated camera), else encoded once at record
  time (:func:`labkit.devices.camera.sources.encode_jpeg`).

Replay (:class:`ReplaySource`) serves exactly the stored bytes, in the stored order, so an
analysis of a replayed burst sees what the live analysis saw, and a recorded fault fails the
replayed burst as it failed the run (:class:`RecordedFault`). ``mode=timed`` also waits on the
clock until each frame's recorded time.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from labkit.devices.camera.frames import CameraSettings, Frame
from labkit.devices.camera.sources import RawFrame, SourceStopped
from labkit.errors import CassetteError, DeviceError, DeviceTimeout

FORMAT = "labkit-frames"
VERSION = 1
#: the camera faults a frame cassette records, by the name stored in its fault lines
FAULTS: dict[str, type[DeviceError]] = {"DeviceError": DeviceError, "DeviceTimeout": DeviceTimeout}


class RecordedFault(Exception):
    """A replayed source reached the fault line of a burst the camera failed: ``kind`` (a class
    of :data:`FAULTS`), the recorded camera's ``device`` name (its URL, not the replay's) and
    the recorded ``reason``, raised again by the camera as recorded."""

    def __init__(self, kind: type[DeviceError], device: str | None, reason: str) -> None:
        super().__init__(reason)
        self.kind = kind
        self.device = device
        self.reason = reason


def is_fault(entry: dict[str, Any]) -> bool:
    """A fault line (a failed burst's end), not a frame."""
    return "fault" in entry


def sidecar_path(index: str | Path) -> Path:
    """``cassettes/camera.jsonl`` -> ``cassettes/camera.mjpeg``."""
    p = Path(index)
    return p.with_suffix(".mjpeg")


class FrameCassetteWriter:
    """Append frames to an index and its byte sidecar (both flushed after every burst)."""

    def __init__(self, index: str | Path, url: str, settings: CameraSettings) -> None:
        self.index_path = Path(index)
        self.index_path.parent.mkdir(parents=True, exist_ok=True)
        self.index = self.index_path.open("w", encoding="utf-8")
        self.data = sidecar_path(self.index_path).open("wb")
        self.offset = 0
        header = {"format": FORMAT, "version": VERSION, "url": url, "settings": settings.as_json()}
        self.index.write(json.dumps(header) + "\n")

    def write(self, frames: list[Frame], step: Any = None) -> None:
        for frame in frames:
            self.data.write(frame.payload)
            entry = {**frame.index_entry(), "offset": self.offset, "step": step}
            self.offset += len(frame.payload)
            self.index.write(json.dumps(entry) + "\n")
        self.data.flush()
        self.index.flush()

    def write_fault(self, error: DeviceError, step: Any, frames_asked: int, t_host: float) -> None:
        """The burst labelled ``step`` ended in ``error`` at ``t_host`` (its frames written before)."""
        kind = type(error).__name__ if type(error).__name__ in FAULTS else "DeviceError"
        entry = {"fault": kind, "device": error.device, "reason": error.reason, "step": step,
                 "frames_asked": frames_asked, "t_host": t_host}
        self.index.write(json.dumps(entry) + "\n")
        self.index.flush()

    def close(self) -> None:
        self.index.close()
        self.data.close()


def read_cassette(index: str | Path) -> tuple[dict[str, Any], list[dict[str, Any]], bytes]:
    """(header, frame entries, sidecar bytes); CassetteError naming file, line and problem."""
    p = Path(index)
    try:
        lines = p.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise CassetteError(str(p), 0, f"cannot read frame cassette: {exc.strerror or exc}") from None
    if not lines:
        raise CassetteError(str(p), 1, "empty frame cassette (no header)")
    entries = []
    for n, line in enumerate(lines, 1):
        try:
            obj = json.loads(line)
        except json.JSONDecodeError as exc:
            raise CassetteError(str(p), n, f"not JSON: {exc.msg}") from None
        if not isinstance(obj, dict):
            raise CassetteError(str(p), n, "expected a JSON object")
        entries.append(obj)
    header = entries.pop(0)
    if header.get("format") != FORMAT:
        raise CassetteError(str(p), 1, f"not a frame cassette (format {header.get('format')!r}, "
                                       f"expected {FORMAT!r})")
    try:
        CameraSettings.from_json(header["settings"])
    except (KeyError, TypeError, ValueError, AttributeError):
        raise CassetteError(str(p), 1, "frame cassette header without usable settings "
                                       "(size WIDTHxHEIGHT, fps, fourcc, ...)") from None
    data_path = sidecar_path(p)
    try:
        data = data_path.read_bytes()
    except OSError as exc:
        raise CassetteError(str(data_path), 0, f"cannot read frame bytes: {exc.strerror or exc}") from None
    for n, e in enumerate(entries, 2):
        if is_fault(e):
            _check_fault(p, n, e)
            continue
        try:
            end = int(e["offset"]) + int(e["length"])
            float(e["t_host"])
            int(e.get("dropped_before") or 0)
        except (KeyError, TypeError, ValueError, OverflowError):
            raise CassetteError(str(p), n, "frame entry without integer offset and length, "
                                           "numeric t_host and dropped_before") from None
        if end > len(data) or int(e["offset"]) < 0:
            raise CassetteError(str(p), n, f"frame bytes {e['offset']}..{end} beyond {data_path.name} "
                                           f"({len(data)} bytes): truncated sidecar")
    return header, entries, data


def _check_fault(path: Path, line: int, entry: dict[str, Any]) -> None:
    try:
        float(entry["t_host"])
        usable = entry["fault"] in FAULTS and isinstance(entry["reason"], str)
    except (KeyError, TypeError, ValueError, OverflowError):
        usable = False
    if not usable:
        raise CassetteError(str(path), line, f"fault line without a known fault ({', '.join(FAULTS)}), "
                                             "a reason and a numeric t_host")


class ReplaySource:
    """``replay://ROLE.jsonl``: the recorded frames, byte for byte, in order (pull mode)."""

    live = False

    def __init__(self, index: str | Path, mode: str = "strict") -> None:
        self.path = str(index)
        self.mode = mode
        self.header, self.entries, self.data = read_cassette(index)
        self.next = 0
        self.clock: Any = None

    def open(self, clock: Any) -> CameraSettings:
        self.clock = clock
        return CameraSettings.from_json(self.header["settings"])

    def read(self, timeout_s: float) -> RawFrame:
        if self.next >= len(self.entries):
            raise SourceStopped(f"has no more frames: the cassette {self.path} holds {len(self.entries)} "
                                "(the replayed run asked for more than the recorded one took)")
        e = self.entries[self.next]
        self.next += 1
        if self.mode == "timed":
            self.clock.sleep_until(float(e["t_host"]))
        if is_fault(e):
            raise RecordedFault(FAULTS[e["fault"]], e.get("device"), e["reason"])
        start = int(e["offset"])
        return RawFrame(self.data[start:start + int(e["length"])], e.get("t_device"), e.get("seq"),
                        t_host=float(e["t_host"]), dropped_before=int(e.get("dropped_before") or 0),
                        meta=e.get("meta"))

    def step_of_next(self) -> Any:
        return self.entries[self.next].get("step") if self.next < len(self.entries) else None

    def close(self) -> None:
        pass
