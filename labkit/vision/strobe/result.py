"""The typed result of ``labkit analyse strobe`` (ADR 0034; keys in docs/reference/vision-json.md).

Every nested object of the JSON is a frozen dataclass here, with ``to_json`` giving its object
key for key; :meth:`StrobeResult.of` builds the result from the object the analysis assembles."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from labkit.vision.shared.result import AnalysisResult, Pattern, RecordedSpeeds, json_of
from labkit.vision.shared.verdict import QualityReport
from labkit.vision.strobe.phase import PhaseModel


def _fields_json(part: Any) -> dict[str, Any]:
    return {f.name: json_of(getattr(part, f.name)) for f in fields(part)}


@dataclass(frozen=True)
class InMillimetres:
    """The lateral amplitude and RC offset in mm (``--mm-per-px`` given): top-level
    ``lateral_amplitude_mm`` and ``rc_offset_mm`` (None without an offset), and the same keys of
    ``uncertainty`` for their standard errors."""

    lateral_amplitude_mm: float
    rc_offset_mm: float | None

    @classmethod
    def scaled(cls, lateral_px: float, rc_offset_px: float | None, mm_per_px: float) -> InMillimetres:
        return cls(lateral_px * mm_per_px, None if rc_offset_px is None else rc_offset_px * mm_per_px)

    def to_json(self) -> dict[str, Any]:
        return {"lateral_amplitude_mm": self.lateral_amplitude_mm, "rc_offset_mm": self.rc_offset_mm}


@dataclass(frozen=True)
class Uncertainty:
    """1-sigma standard errors of the amplitudes (``uncertainty``), how they were found, and in mm
    when the scale was given."""

    tilt_amplitude_rad: float
    lateral_amplitude_px: float
    rc_offset_px: float | None
    method: str
    in_mm: InMillimetres | None = None

    def to_json(self) -> dict[str, Any]:
        out = {"tilt_amplitude_rad": self.tilt_amplitude_rad,
               "lateral_amplitude_px": self.lateral_amplitude_px, "rc_offset_px": self.rc_offset_px,
               "method": self.method}
        return out if self.in_mm is None else {**out, **self.in_mm.to_json()}


@dataclass(frozen=True)
class RoomLight:
    """The room light's ghost taken out (``room_light``; docs/explanation/strobe-analysis.md, Room
    light): its share of the light, the rounds of the fit and the amplitudes before."""

    method: str
    fraction_of_light: float
    rounds: int
    settled: bool
    last_change: float | None
    frames_fitted: int
    tilt_amplitude_uncorrected_rad: float
    lateral_amplitude_uncorrected_px: float
    # the tilt on the frames fitted, before the whole clip was measured (None: a result of strobe
    # analysis version 1, which did not keep it)
    tilt_amplitude_fitted_frames_rad: float | None = None

    def to_json(self) -> dict[str, Any]:
        return _fields_json(self)


@dataclass(frozen=True)
class PerFrame:
    """What the Eq. 5.97 fit was given, frame by frame (``per_frame``): frame index, tilt, lateral
    position."""

    index: list[int]
    tilt_rad: list[float]
    lateral_px: list[float]

    def to_json(self) -> dict[str, Any]:
        return _fields_json(self)


@dataclass(frozen=True, kw_only=True)
class PointPattern(Pattern):
    """The curve the tracked body point draws against the rotor phase (``point_pattern``); a
    pattern of type ``none`` writes only its type and reason."""

    def to_json(self) -> dict[str, Any]:
        if not self.found:
            return {"type": self.type, "reason": self.reason}
        return {"type": self.type, **self._curve_json(False)}


@dataclass(frozen=True)
class BodyAxis:
    """The body (``body``): rest axis from image +x in deg, n-fold symmetry, half length in px."""

    rest_axis_deg: float
    symmetry: int
    half_length_px: float

    def to_json(self) -> dict[str, Any]:
        return _fields_json(self)


@dataclass(frozen=True)
class LensBlur:
    """The per-row model's lens blur: core and halo widths in px and the halo's share."""

    core: float
    halo: float
    halo_fraction: float

    def to_json(self) -> dict[str, Any]:
        return _fields_json(self)


@dataclass(frozen=True)
class RollingShutterFit:
    """The per-row phase model's fit (``rolling_shutter``; docs/explanation/strobe-analysis.md):
    amplitudes with their standard errors, readout, how well the rows are explained, and the fit's
    own bookkeeping."""

    model: str
    tilt_amplitude_rad: float
    tilt_amplitude_se_rad: float
    lateral_amplitude_px: float
    lateral_amplitude_se_px: float
    rc_offset_px: float
    rc_offset_se_px: float
    towards_top: bool | None
    magnet_axis_deg: float
    readout_s: float
    readout_se_s: float
    readout_given: bool
    line_time_s: float
    readout_at_bound: bool
    rows_explained: float
    rows_explained_one_phase_per_frame: float
    ends_separation: float | None
    long_side_from_rows_deg: float
    rms_residual: float
    noise: float
    residual_noise_ratio: float
    correlation_area_px: float
    frames_fitted: int
    bin: int
    pixels_fitted: int
    iterations: int
    converged: bool
    lens_blur_px: LensBlur

    @classmethod
    def from_json(cls, fit: dict[str, Any]) -> RollingShutterFit:
        return cls(**{**fit, "lens_blur_px": LensBlur(**fit["lens_blur_px"])})

    def to_json(self) -> dict[str, Any]:
        return _fields_json(self)


@dataclass(frozen=True)
class OverlayFrame:
    """The first frame with a body and what the overlay draws on it, in px: centre, axis (unit
    vector to the top end), rest axis, half length, the body's half diagonal (``radius_px``), the
    tracked point and its track over every frame. No part of the JSON."""

    index: int
    bgr: np.ndarray
    centre: list[float]
    axis: list[float]
    rest_axis: list[float]
    half_length_px: float
    point: list[float]
    track: list[list[float]]
    radius_px: float


@dataclass(frozen=True)
class StrobeResult(AnalysisResult):
    """What :func:`labkit.vision.strobe.analyse.analyse_strobe` found (Eq. 5.97); ``to_json()`` is
    the JSON. ``overlay_frame`` (``keep_frame=True``) is no part of the JSON."""

    NOT_IN_JSON = frozenset({"in_mm", "speeds", "overlay_frame"})

    source: str
    frames: int
    fps: float
    apparent_hz: float
    tilt_amplitude_rad: float
    lateral_amplitude_px: float
    rc_offset_px: float | None
    uncertainty: Uncertainty
    room_light: RoomLight | None
    phase_per_frame: list[float]
    per_frame: PerFrame
    point_pattern: PointPattern
    rc_offset_direction: str | None
    phase_source: str
    phase_model: PhaseModel
    body: BodyAxis
    quality: QualityReport
    rolling_shutter: RollingShutterFit | None = None  # the per-row model's fit; absent when None
    in_mm: InMillimetres | None = None
    speeds: RecordedSpeeds | None = None
    overlay_frame: OverlayFrame | None = None

    @classmethod
    def of(cls, out: dict[str, Any], in_mm: InMillimetres | None, se_mm: InMillimetres | None,
           overlay_frame: OverlayFrame | None) -> StrobeResult:
        """From the analysis' object (JSON values, the phase model as the analysis used it)."""
        room, rolling = out["room_light"], out.get("rolling_shutter")
        return cls(**{**out, "uncertainty": Uncertainty(**out["uncertainty"], in_mm=se_mm),
                      "room_light": None if room is None else RoomLight(**room),
                      "per_frame": PerFrame(**out["per_frame"]),
                      "point_pattern": PointPattern(**PointPattern.parts_from_json(out["point_pattern"])),
                      "body": BodyAxis(**out["body"]), "quality": QualityReport.from_json(out["quality"]),
                      "rolling_shutter": None if rolling is None else RollingShutterFit.from_json(rolling)},
                   in_mm=in_mm, overlay_frame=overlay_frame)

    def _json_tail(self) -> dict[str, Any]:
        if self.in_mm is None:
            return {}
        return self.in_mm.to_json()
