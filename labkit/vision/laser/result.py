"""The typed result of ``labkit analyse laser`` (ADR 0034; keys in docs/reference/vision-json.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from labkit.vision.shared.result import AnalysisResult, Pattern, RecordedSpeeds
from labkit.vision.shared.verdict import QualityReport


@dataclass(frozen=True, kw_only=True)
class LaserPattern(Pattern):
    """The trace's pattern (``pattern``): every parameter key is written, null where it does not
    apply; ``symmetry`` is the n-fold rotational symmetry (None for a circle and for ``none``)."""

    symmetry: int | None = None

    def to_json(self) -> dict[str, Any]:
        head: dict[str, Any] = {"type": self.type}
        if self.reason is not None:
            head["reason"] = self.reason
        return {**head, **self._curve_json(True, self.symmetry)}

    @classmethod
    def from_json(cls, pattern: dict[str, Any]) -> LaserPattern:
        return cls(**cls.parts_from_json(pattern))


@dataclass(frozen=True)
class TiltAngles:
    """The tilt (``tilt_rad``) from the pattern's semi-axes and the screen geometry, in rad."""

    major: float
    minor: float

    def to_json(self) -> dict[str, Any]:
        return {"major": self.major, "minor": self.minor}


@dataclass(frozen=True)
class LaserResult(AnalysisResult):
    """What :func:`labkit.vision.laser.analyse.analyse_laser` found; ``to_json()`` is the JSON."""

    NOT_IN_JSON = frozenset({"speeds"})

    source: str
    frames: int
    fps: float
    size: list[int]
    pattern: LaserPattern  # type "none" (with a reason) when no pattern was read
    tilt_rad: TiltAngles | None  # with the screen geometry (--screen-distance-mm and --mm-per-px)
    quality: QualityReport  # verdict, reasons, checks, then the evidence
    speeds: RecordedSpeeds | None = None

    @property
    def found_pattern(self) -> bool:
        return self.pattern.found
