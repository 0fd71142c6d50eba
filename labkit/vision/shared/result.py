"""What the two analyses' typed results share (ADR 0034): the top-level keys of the JSON are
attributes, :meth:`AnalysisResult.to_json` gives the JSON exactly as the commands write it (key
order included), and a read-only mapping face over that JSON keeps ``result["quality"]`` working
for scripts written against the dict results. Nested objects (``pattern``, the ``quality``
evidence, ``rolling_shutter``) stay dicts: their keys are docs/reference/vision-json.md's."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, fields
from functools import cached_property
from typing import Any


@dataclass(frozen=True)
class RecordedSpeeds:
    """The rotor speed and floator spin recorded while filming (``--speed-rpm``, ``--spin-rad-s``;
    None when not known): the top-level ``rotor_speed_rpm`` and ``spin_rad_s`` that
    ``labkit.fit.data`` reads to put a clip's cone angle against its rotor speed (Eq. 5.24)."""

    rotor_speed_rpm: float | None
    spin_rad_s: float | None

    def to_json(self) -> dict[str, Any]:
        return {"rotor_speed_rpm": self.rotor_speed_rpm, "spin_rad_s": self.spin_rad_s}


class AnalysisResult(Mapping[str, Any]):
    """Base of :class:`labkit.vision.laser.result.LaserResult` and
    :class:`labkit.vision.strobe.result.StrobeResult` (frozen dataclasses)."""

    #: fields that are no key of the JSON (they are written in ``to_json`` or not at all)
    NOT_IN_JSON: frozenset[str] = frozenset()

    quality: dict[str, Any]
    speeds: RecordedSpeeds | None

    @property
    def verdict(self) -> str:
        """``ok``, ``doubtful`` or ``failed`` (docs/reference/vision-verdicts.md)."""
        return str(self.quality["verdict"])

    @property
    def reasons(self) -> list[str]:
        """Why the verdict is not ``ok``, most important first."""
        return list(self.quality.get("reasons") or [])

    def to_json(self) -> dict[str, Any]:
        """The JSON object of ``labkit analyse ... --json`` (a fresh dict; nested objects shared)."""
        out: dict[str, Any] = {}
        for f in fields(self):  # type: ignore[arg-type]  # every subclass is a dataclass
            value = getattr(self, f.name)
            if f.name in self.NOT_IN_JSON or (value is None and f.default is None):
                continue  # optional keys are absent from the JSON, not null
            out[f.name] = value
        out.update(self._json_tail())
        if self.speeds is not None:
            out.update(self.speeds.to_json())
        return out

    def _json_tail(self) -> dict[str, Any]:
        """Keys a subclass derives after its fields (none here)."""
        return {}

    @cached_property
    def _json(self) -> dict[str, Any]:
        return self.to_json()

    def __getitem__(self, key: str) -> Any:
        return self._json[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._json)

    def __len__(self) -> int:
        return len(self._json)
