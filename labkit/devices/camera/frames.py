"""What a camera delivers: :class:`Frame` (the bytes as the camera sent them, with a sequence
number and its times) and :class:`CameraSettings` (what the camera accepted, read back).

Times are seconds on the run's clock (:mod:`labkit.io.clock`). ``t_host`` is when the frame
reached labkit (the grab thread's dequeue); ``t_device`` is the camera's own timestamp mapped
onto the run's clock where the source has one (V4L2 buffer timestamps, the emulated camera's
exposure start) and None otherwise (network streams: their timestamps are synthetic).
``trusted`` says which of the two ``t`` is: ``"device"`` or ``"host"``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

TIMESTAMP_KINDS = ("device", "host")


@dataclass(frozen=True)
class Frame:
    """One frame: ``payload`` are the bytes as stored (JPEG), ``seq`` the camera's sequence number
    (counted by labkit where the camera has none), ``dropped_before`` frames lost since the previous
    one (a sequence gap, or a time gap of more than 1.5 frame periods)."""

    seq: int
    t_host: float
    t_device: float | None
    payload: bytes
    dropped_before: int = 0
    fmt: str = "jpeg"
    #: what the source adds (the emulated camera: the model's cone angle and speed); stored
    meta: dict[str, Any] | None = None

    @property
    def trusted(self) -> str:
        """Which time ``t`` is: ``"device"`` when the source stamps frames, else ``"host"``."""
        return "device" if self.t_device is not None else "host"

    @property
    def t(self) -> float:
        """The frame's time on the run's clock: the device timestamp if there is one, else arrival."""
        return self.t_device if self.t_device is not None else self.t_host

    def image(self) -> np.ndarray:
        """The frame decoded to 8-bit BGR (ValueError if the bytes are not an image)."""
        import cv2
        import numpy as np

        img = cv2.imdecode(np.frombuffer(self.payload, np.uint8), cv2.IMREAD_COLOR)
        if img is None:
            raise ValueError(f"frame {self.seq}: {len(self.payload)} bytes do not decode as {self.fmt}")
        return img

    def index_entry(self) -> dict[str, Any]:
        """The frame's line in a cassette index (without the byte offset)."""
        entry = {"seq": self.seq, "t_host": self.t_host, "t_device": self.t_device, "trusted": self.trusted,
                 "dropped_before": self.dropped_before, "length": len(self.payload), "fmt": self.fmt}
        return {**entry, "meta": self.meta} if self.meta else entry


@dataclass(frozen=True)
class CameraSettings:
    """What the camera accepted (read back after setting), not what was asked.

    ``fps`` is the driver's nominal rate (None when the source does not say: network streams
    invent one); ``exposure_s`` None when unknown or automatic; ``timestamps``: ``device`` or
    ``host`` (which time frames will carry as trusted)."""

    size: tuple[int, int]
    fps: float | None
    fourcc: str
    exposure_s: float | None
    timestamps: str
    backend: str
    requested: dict[str, Any]

    def as_json(self) -> dict[str, Any]:
        d = asdict(self)
        d["size"] = f"{self.size[0]}x{self.size[1]}"
        return d

    @classmethod
    def from_json(cls, obj: dict[str, Any]) -> CameraSettings:
        w, h = (int(x) for x in str(obj["size"]).split("x"))
        if w <= 0 or h <= 0:
            raise ValueError(f"size {obj['size']!r}")
        return cls((w, h), obj.get("fps"), str(obj.get("fourcc", "")), obj.get("exposure_s"),
                   str(obj.get("timestamps", "host")), str(obj.get("backend", "")),
                   dict(obj.get("requested") or {}))
