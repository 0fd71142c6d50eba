"""What the two analyses' typed results share (ADR 0034): the top-level keys of the JSON are
attributes, every nested object of the JSON is a typed part (frozen dataclasses with a
``to_json``), and :meth:`AnalysisResult.to_json` gives the JSON exactly as the commands write it
(key order included; docs/reference/vision-json.md). The quality verdict is
:class:`labkit.vision.shared.verdict.QualityReport`, one type for both pipelines."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from labkit.vision.shared.verdict import QualityReport


def json_of(value: Any) -> Any:
    """A typed part's JSON (its ``to_json()``), anything else as it is."""
    to_json = getattr(value, "to_json", None)
    return to_json() if callable(to_json) else value


@dataclass(frozen=True)
class RecordedSpeeds:
    """The rotor speed and floator spin recorded while filming (``--speed-rpm``, ``--spin-rad-s``;
    None when not known): the top-level ``rotor_speed_rpm`` and ``spin_rad_s`` that
    ``labkit.fit.data`` reads to put a clip's cone angle against its rotor speed (Eq. 5.24)."""

    rotor_speed_rpm: float | None
    spin_rad_s: float | None

    def to_json(self) -> dict[str, Any]:
        return {"rotor_speed_rpm": self.rotor_speed_rpm, "spin_rad_s": self.spin_rad_s}


@dataclass(frozen=True)
class Trochoid:
    """A trochoid's own parameters (Eq. 6.38): ``a`` and ``b``, the scale in px and the rotation."""

    a: float
    b: float
    scale_px: float
    rotation_deg: float

    def to_json(self) -> dict[str, Any]:
        return {"a": self.a, "b": self.b, "scale_px": self.scale_px, "rotation_deg": self.rotation_deg}


@dataclass(frozen=True, kw_only=True)
class Pattern:
    """A closed curve read from the light (the laser's trace, the strobe's tracked point):
    ``type`` is ``circle``, ``ellipse``, ``epitrochoid``, ``hypotrochoid`` or ``none``; a pattern of
    type ``none`` has the ``reason`` and no parameters. Trochoids have ``trochoid`` and no
    ``ellipticity``; ``semi_axes_px`` is the extent (largest and smallest distance from the centre)."""

    type: str
    reason: str | None = None
    center_px: list[float] | None = None
    semi_axes_px: list[float] | None = None
    rotation_deg: float | None = None
    ellipticity: float | None = None
    loops: int | None = None
    trochoid: Trochoid | None = None
    rms_residual_px: float | None = None

    @property
    def found(self) -> bool:
        """A curve was read (``type`` is not ``none``)."""
        return self.type != "none"

    def _curve_json(self, with_symmetry: bool, symmetry: int | None = None) -> dict[str, Any]:
        out: dict[str, Any] = {"center_px": self.center_px, "semi_axes_px": self.semi_axes_px,
                               "rotation_deg": self.rotation_deg, "ellipticity": self.ellipticity,
                               "loops": self.loops}
        if with_symmetry:
            out["symmetry"] = symmetry
        out["trochoid"] = json_of(self.trochoid)
        out["rms_residual_px"] = self.rms_residual_px
        return out

    @staticmethod
    def parts_from_json(pattern: dict[str, Any]) -> dict[str, Any]:
        """The keyword arguments of a pattern from its JSON object."""
        t = pattern.get("trochoid")
        return {**pattern, "trochoid": None if t is None else Trochoid(**t)}


class AnalysisResult:
    """Base of :class:`labkit.vision.laser.result.LaserResult` and
    :class:`labkit.vision.strobe.result.StrobeResult` (frozen dataclasses)."""

    #: fields that are no key of the JSON (they are written in ``to_json`` or not at all)
    NOT_IN_JSON: frozenset[str] = frozenset()

    quality: QualityReport
    speeds: RecordedSpeeds | None

    @property
    def verdict(self) -> str:
        """``ok``, ``doubtful`` or ``failed`` (docs/reference/vision-verdicts.md)."""
        return self.quality.verdict

    @property
    def reasons(self) -> list[str]:
        """Why the verdict is not ``ok``, most important first."""
        return list(self.quality.reasons)

    def to_json(self) -> dict[str, Any]:
        """The JSON object of ``labkit analyse ... --json`` (a fresh dict of JSON values)."""
        out: dict[str, Any] = {}
        for f in fields(self):  # type: ignore[arg-type]  # every subclass is a dataclass
            value = getattr(self, f.name)
            if f.name in self.NOT_IN_JSON or (value is None and f.default is None):
                continue  # optional keys are absent from the JSON, not null
            out[f.name] = json_of(value)
        out.update(self._json_tail())
        if self.speeds is not None:
            out.update(self.speeds.to_json())
        return out

    def _json_tail(self) -> dict[str, Any]:
        """Keys a subclass derives after its fields (none here)."""
        return {}
