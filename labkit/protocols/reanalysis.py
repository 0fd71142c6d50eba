"""What a protocol's analysis-only rule gets (``ProtocolDef.reanalyse_step``, called by
:mod:`labkit.protocols.reanalyse` for ``labkit replay --analysis-only``): the recorded session,
its rig and resolved parameters, every device's readings parsed again from their bytes
(:class:`Parsed`), the frame cassette's bursts (:class:`FrameBursts`) and a list for notes.
The rules themselves live with their protocols, beside the run's own rule they repeat."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from labkit.devices.camera.frames import Frame
from labkit.session import SessionRecord


@dataclass(frozen=True)
class Parsed:
    """A re-parsed reading: what the protocols use of a :class:`~labkit.devices.base.Reading`."""

    t: float
    value: float
    unit: str
    stable: bool
    overload: bool = False


class FrameBursts:
    """A session's frame cassette (``cassettes/ROLE.jsonl`` and its sidecar), its frames grouped
    by burst (the camera's ``step`` label, ``STEP.TAKE``), as the camera's own :class:`Frame` s
    with their stored bytes and ``meta``."""

    def __init__(self, record: SessionRecord, role: str = "camera") -> None:
        from labkit.devices.camera.cassette import is_fault, read_cassette

        header, entries, data = read_cassette(record.path / "cassettes" / f"{role}.jsonl")
        entries = [e for e in entries if not is_fault(e)]  # a failed burst's fault line: no point was made
        self.settings: dict[str, Any] = dict(header.get("settings") or {})
        width, height = (int(v) for v in str(self.settings["size"]).split("x"))
        self.size = (width, height)
        self.fps: float | None = self.settings.get("fps")
        self.exposure_s: float | None = self.settings.get("exposure_s")
        self.bursts: dict[str, list[Frame]] = {}
        for e in entries:
            start = int(e["offset"])
            t_device = e.get("t_device")
            self.bursts.setdefault(str(e.get("step")), []).append(Frame(
                int(e.get("seq") or 0), float(e["t_host"]), None if t_device is None else float(t_device),
                data[start:start + int(e["length"])], int(e.get("dropped_before") or 0),
                str(e.get("fmt") or "jpeg"), e.get("meta")))

    def frames(self, step: int, take: int) -> list[Frame]:
        """The frames of step ``step``'s burst ``take`` (0, or 1 for a retake); [] if none."""
        return self.bursts.get(f"{step}.{take}", [])


@dataclass
class RecordedRun:
    """One session as an analysis-only rule sees it (module docstring)."""

    record: SessionRecord
    rig: Any
    params: dict[str, Any]
    readings: dict[str, list[Parsed]]
    notes: list[str] = field(default_factory=list)
    _bursts: dict[str, FrameBursts] = field(default_factory=dict)

    def bursts(self, role: str = "camera") -> FrameBursts:
        """The frame cassette of ``role``, read once."""
        if role not in self._bursts:
            self._bursts[role] = FrameBursts(self.record, role)
        return self._bursts[role]


def point_event(events: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The recorded point of one step's events (None if the step made none)."""
    point = next((e["point"] for e in events if e.get("type") == "point"), None)
    return point if isinstance(point, dict) else None
