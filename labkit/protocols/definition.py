"""What a protocol is: :class:`ProtocolDef` (its parameters, the devices it needs, its plan,
its step, its quick fit and what it declares about its data) and the :class:`Step` s it plans.

The runner (:mod:`labkit.protocols.runner`) runs one; its declarations (``bounds``, ``row``,
``hints``: :mod:`labkit.hints`, :mod:`labkit.protocols.declaration`) go into the run's start
document, where the live view and the report read them (docs/reference/protocols.md,
docs/how-to/add-a-protocol.md, ADR 0021).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from labkit.hints import Column, Hints

if TYPE_CHECKING:
    from labkit.protocols.context import RunContext
    from labkit.protocols.reanalysis import RecordedRun
    from labkit.rig import Rig
    from labkit.vision.shared.versions import AnalysisVersion


@dataclass
class Step:
    """One planned step: targets per speed loop (rad/s) and protocol data."""

    index: int
    label: str
    targets_rad_s: dict[str, float]
    data: dict[str, Any] = field(default_factory=dict)
    est_duration_s: float = 0.0


class ProtocolDef:
    """Base of a protocol: ``defaults`` (keys with unit suffixes), ``needs`` ((role, kind), ...),
    ``bounds`` (name -> (low, high) within the caps of the suffix, None for no bound), ``row``
    (the columns a step's result row has, with units) and ``hints`` (its figure and fits)."""

    name: str = ""
    summary: str = ""
    defaults: dict[str, Any] = {}
    needs: tuple[tuple[str, str], ...] = ()
    bounds: dict[str, tuple[float | None, float | None]] = {}
    row: tuple[Column, ...] = ()
    hints: Hints | None = None
    #: the image analysis a step runs on its frames, if any: its version goes into run.json and
    #: the replay compares its row's ``Column.accuracy`` keys by it (labkit.protocols.analysis_versions)
    image_analysis: AnalysisVersion | None = None

    def plan(self, rig: Rig, params: dict[str, Any]) -> list[Step]:  # pragma: no cover - interface
        raise NotImplementedError

    def run_step(self, ctx: RunContext, step: Step) -> dict[str, Any]:  # pragma: no cover
        raise NotImplementedError

    def setup(self, ctx: RunContext) -> None:
        """Once, after the rig is open and before the first step (e.g. tare the balance)."""

    def fit(self, points: list[dict[str, Any]]) -> dict[str, Any]:
        return {"model": "none", "params": {}}

    def reanalyse_step(self, run: RecordedRun, step: int,
                       events: list[dict[str, Any]]) -> dict[str, Any] | None:
        """The analysis-only rule (``labkit replay --analysis-only``, docs/explanation/replay.md):
        step ``step``'s point computed again from the session's bytes (``run``: the re-parsed
        readings, the frame cassette) and its recorded decisions (``events``, the step's lines of
        events.jsonl), by the same rule the run used; None where the step made no point.
        A protocol without a rule leaves this: its points are then taken as recorded, and the
        replay says so."""
        raise NotImplementedError
