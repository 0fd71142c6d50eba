"""The typed result of ``labkit analyse laser`` (ADR 0034; keys in docs/reference/vision-json.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from labkit.vision.shared.result import AnalysisResult, RecordedSpeeds


@dataclass(frozen=True)
class LaserResult(AnalysisResult):
    """What :func:`labkit.vision.laser.analyse.analyse_laser` found; ``to_json()`` is the JSON."""

    NOT_IN_JSON = frozenset({"speeds"})

    source: str
    frames: int
    fps: float
    size: list[int]
    pattern: dict[str, Any]  # "type" is "none" (with a "reason") when no pattern was read
    tilt_rad: dict[str, float] | None  # {"major", "minor"} with the screen geometry, else None
    quality: dict[str, Any]  # verdict, reasons, checks, then the evidence
    speeds: RecordedSpeeds | None = None

    @property
    def found_pattern(self) -> bool:
        return self.pattern.get("type", "none") != "none"
