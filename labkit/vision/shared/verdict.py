"""Quality verdicts of a vision result: ``ok``, ``doubtful`` or ``failed`` with reasons in words.

Every analysis (laser, strobe) turns its evidence into :class:`Finding` objects, one per thing a
reviewer would check (residual against line width, coverage, size against the frame ...); each
finding says ``ok``, ``doubtful`` or ``failed`` and, when not ``ok``, why. The verdict of the
result is the worst finding, and its reasons are those of the findings that are not ``ok``
(docs/reference/vision-verdicts.md, "Quality verdict"). The JSON shape is

    "quality": {"verdict": "ok" | "doubtful" | "failed", "reasons": [...], ...evidence...}

at the top level of the result. Pure functions, no I/O.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

VERDICTS = ("ok", "doubtful", "failed")


@dataclass(frozen=True)
class Finding:
    """One check: its name, its verdict and (unless ``ok``) the reason in words."""

    check: str
    verdict: str
    reason: str = ""

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {', '.join(VERDICTS)}, got {self.verdict!r}")
        if self.verdict != "ok" and not self.reason:
            raise ValueError(f"a {self.verdict} finding ({self.check}) needs a reason")


def graded(check: str, value: float, doubtful_above: float, failed_above: float, reason: str) -> Finding:
    """A finding from a measure where larger is worse: ``ok`` up to ``doubtful_above``,
    ``doubtful`` up to ``failed_above``, else ``failed``; ``reason`` is formatted with ``value``
    (``{value}``) when the finding is not ``ok``. A NaN value is ``doubtful`` (not measured)."""
    if value != value:  # NaN
        return Finding(check, "doubtful", f"{check} could not be measured")
    if value <= doubtful_above:
        return Finding(check, "ok")
    verdict = "doubtful" if value <= failed_above else "failed"
    return Finding(check, verdict, reason.format(value=value))


def worst(verdicts: Iterable[str]) -> str:
    """The worst of several verdicts (``ok`` for none)."""
    return max(verdicts, key=VERDICTS.index, default="ok")


def verdict(findings: Iterable[Finding]) -> dict:
    """``{"verdict", "reasons", "checks"}``: the worst finding, the reasons of every finding that
    is not ``ok`` (failed first), and each check's own verdict by name."""
    found = list(findings)
    bad = sorted((f for f in found if f.verdict != "ok"), key=lambda f: -VERDICTS.index(f.verdict))
    return {"verdict": worst(f.verdict for f in found), "reasons": [f.reason for f in bad],
            "checks": {f.check: f.verdict for f in found}}


def in_words(quality: dict) -> str:
    """The verdict as a sentence for the terminal: ``result ok`` or ``result doubtful: r1; r2``."""
    v = quality.get("verdict", "ok")
    reasons = quality.get("reasons") or []
    return f"result {v}" + (": " + "; ".join(reasons) if reasons else "")


def rank(quality: dict) -> tuple[int, int]:
    """Order of two results of the same clip, better first: by verdict, and between equal verdicts
    by how many checks are not ``ok`` (a doubtful fit with one reason beats one with six)."""
    return VERDICTS.index(quality.get("verdict", "ok")), len(quality.get("reasons") or [])
