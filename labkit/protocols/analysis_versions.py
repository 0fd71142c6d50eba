"""The image-analysis versions a session was made with, and how a replay compares its numbers
(docs/explanation/replay.md#analysis-versions, docs/decisions/0040-analysis-versions-and-the-laser-speed.md).

A protocol that analyses frames names its analysis (``ProtocolDef.image_analysis``, a
:class:`~labkit.vision.shared.versions.AnalysisVersion`); the run records its version in
``run.json`` (``"analyses": {"laser": 1}``, :func:`versions_of`). A session without the key was
made before analyses had versions: version 1. When the replay's version is the recorded one,
the row's image-analysis numbers are compared within relative 1e-6 as before; when it is
another, each ``Column.accuracy`` key is compared within the analysis's stated accuracy for
that quantity (:class:`CrossVersion`), and the replay says so.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from labkit.protocols.replay_compare import diff_results
from labkit.protocols.runner import fit_or_error, normalise
from labkit.vision.shared.versions import FIRST_VERSION, Accuracy, AnalysisVersion, is_number

#: run.json's key: analysis name -> version
RUN_KEY = "analyses"


def versions_of(protocol: Any) -> dict[str, int]:
    """What run.json records for a run of ``protocol``: its image analysis's version ({} without)."""
    analysis: AnalysisVersion | None = getattr(protocol, "image_analysis", None)
    return {analysis.name: analysis.version} if analysis is not None else {}


def recorded_version(meta: dict[str, Any], name: str) -> int:
    """The version of analysis ``name`` a session's run.json records (:data:`FIRST_VERSION` for a
    session from before versions)."""
    versions = meta.get(RUN_KEY)
    value = versions.get(name) if isinstance(versions, dict) else None
    return int(value) if isinstance(value, int) and not isinstance(value, bool) else FIRST_VERSION


@dataclass(frozen=True)
class CrossVersion:
    """A session analysed by another version of its protocol's image analysis than the replay's:
    per row key, the stated :class:`Accuracy` it is compared within, and the key its tolerance is
    a share of (``Column.accuracy_of``)."""

    analysis: AnalysisVersion
    recorded: int
    accuracy: dict[str, Accuracy] = field(default_factory=dict)
    of: dict[str, str] = field(default_factory=dict)

    def agrees(self, key: str, a: Any, b: Any, row_a: Any = None, row_b: Any = None) -> bool:
        """Whether the values ``a`` (replay) and ``b`` (recording) of ``key`` agree within the
        stated accuracy (``row_a``, ``row_b``: the points they belong to, for ``accuracy_of``)."""
        other = None
        if key in self.of:
            refs = [r.get(self.of[key]) for r in (row_a, row_b) if isinstance(r, dict)]
            numbers = [abs(float(v)) for v in refs if is_number(v)]
            other = max(numbers) if numbers else None
        return self.accuracy[key].agrees(a, b, other)

    def words(self, key: str) -> str:
        """The tolerance of ``key`` in words, e.g. ``the laser analysis's stated accuracy (1 %)``."""
        return f"the {self.analysis.name} analysis's stated accuracy ({self.accuracy[key].words})"

    def note(self) -> str:
        """What the replay reports, e.g. ``analysis laser 2, recorded with 1: compared within ...``."""
        return (f"analysis {self.analysis.name} {self.analysis.version}, recorded with {self.recorded}: "
                f"compared within its stated accuracy ({self.analysis.describe()}), not relative 1e-6; "
                "the recorded fit checked as the fit of the recorded points")


def cross_version(protocol: Any, meta: dict[str, Any]) -> CrossVersion | None:
    """None when the replay's image analysis is the one the session was made with (or the
    protocol analyses no frames); else the :class:`CrossVersion` to compare by."""
    analysis: AnalysisVersion | None = getattr(protocol, "image_analysis", None)
    if analysis is None:
        return None
    recorded = recorded_version(meta, analysis.name)
    if recorded == analysis.version:
        return None
    accuracy, of = {}, {}
    for column in protocol.row:
        if column.accuracy:
            accuracy[column.name] = analysis.accuracy[column.accuracy]
            if column.accuracy_of:
                of[column.name] = column.accuracy_of
    return CrossVersion(analysis, recorded, accuracy, of)


def recorded_fit_diffs(protocol: Any, recorded: dict[str, Any]) -> list[str]:
    """A faithful replay's check of the fit (and any level's, for a session made by another version
    of its image analysis): ``results.json``'s fit must be what the protocol's
    fit gives for ``results.json``'s points (within :data:`~labkit.protocols.replay_compare.REPLAY_FIT_RTOL`,
    as at the exact level). The replay's own fit is the fit of its points, each within its
    tolerance, and is not compared with the recorded one: a parameter the points determine
    poorly moves with them by more than any fixed share (cone-sweep's tau_S/I, a 1 % correction
    to I omega^2, moved 4 % and two of its standard errors when one speed moved by 0.02 %)."""
    fit = fit_or_error(protocol, list(recorded.get("points") or []))
    return [f"{line} (the fit of results.json's own points)"
            for line in diff_results(normalise(fit), recorded.get("fit"), "results.fit", derived=True)]


def diff_points_then_fit(protocol: Any, replayed: dict[str, Any], recorded: dict[str, Any],
                         compare: Callable[[Any, Any], list[str]]) -> list[str]:
    """A replay's results against ``results.json`` where the replay's fit is not held against the
    recorded one (the faithful level, and any level for a session made by another version of its
    image analysis): everything but the fit by ``compare``, and the recorded fit as the fit of
    the recorded points (:func:`recorded_fit_diffs`)."""
    without_fit = compare({**replayed, "fit": None}, {**recorded, "fit": None})
    return without_fit + recorded_fit_diffs(protocol, recorded)
