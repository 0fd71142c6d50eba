"""The typed result of ``labkit analyse strobe`` (ADR 0034; keys in docs/reference/vision-json.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from labkit.vision.shared.result import AnalysisResult, RecordedSpeeds


@dataclass(frozen=True)
class InMillimetres:
    """The lateral amplitude and RC offset in mm (``--mm-per-px`` given): top-level
    ``lateral_amplitude_mm`` and ``rc_offset_mm`` (None without an offset)."""

    lateral_amplitude_mm: float
    rc_offset_mm: float | None

    @classmethod
    def scaled(cls, lateral_px: float, rc_offset_px: float | None, mm_per_px: float) -> InMillimetres:
        return cls(lateral_px * mm_per_px, None if rc_offset_px is None else rc_offset_px * mm_per_px)


@dataclass(frozen=True)
class StrobeResult(AnalysisResult):
    """What :func:`labkit.vision.strobe.analyse.analyse_strobe` found (Eq. 5.97); ``to_json()`` is
    the JSON. ``overlay_frame`` (``keep_frame=True``) is the first frame with a body and what the
    overlay draws on it; it is no part of the JSON."""

    NOT_IN_JSON = frozenset({"in_mm", "speeds", "overlay_frame"})

    source: str
    frames: int
    fps: float
    apparent_hz: float
    tilt_amplitude_rad: float
    lateral_amplitude_px: float
    rc_offset_px: float | None
    uncertainty: dict[str, Any]
    room_light: dict[str, Any] | None
    phase_per_frame: list[float]
    per_frame: dict[str, list]
    point_pattern: dict[str, Any]
    rc_offset_direction: str | None
    phase_source: str
    phase_model: dict[str, Any]
    body: dict[str, Any]
    quality: dict[str, Any]
    rolling_shutter: dict[str, Any] | None = None  # the per-row model's fit; absent from the JSON when None
    in_mm: InMillimetres | None = None
    speeds: RecordedSpeeds | None = None
    overlay_frame: dict[str, Any] | None = None

    def _json_tail(self) -> dict[str, Any]:
        if self.in_mm is None:
            return {}
        return {"lateral_amplitude_mm": self.in_mm.lateral_amplitude_mm,
                "rc_offset_mm": self.in_mm.rc_offset_mm}
