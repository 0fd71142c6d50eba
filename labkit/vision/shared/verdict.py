"""Quality verdicts of a vision result, one type for both pipelines: ``ok``, ``doubtful`` or
``failed`` with reasons in words (docs/reference/vision-verdicts.md, "Quality verdict").

Every analysis turns its evidence into checks a reviewer would make (residual against line
width, coverage, size against the frame, the phase spread ...). The laser's checks are
:class:`Finding` objects, one per named check (:func:`graded` makes one from a measure and two
limits), combined by :meth:`Verdict.of`; the strobe's checks call :meth:`Verdict.doubt` and
:meth:`Verdict.fail` as they go. Either way the verdict is the worst finding and the reasons are
those of the findings that are not ``ok``, failures first: within one pass of checks in the
order they ran (:meth:`Verdict.of`), while a failure added afterwards (:meth:`Verdict.fail`,
e.g. "this looks like a stroboscope clip") reads before every earlier reason, since it explains
them. The JSON shape is

    "quality": {"verdict": "ok" | "doubtful" | "failed", "reasons": [...], ["checks": {...}],
                ...evidence...}

at the top level of the result; ``checks`` (each named check's verdict) is the laser's. In a
result it is a :class:`QualityReport`: the verdict's fields typed, the evidence an open mapping.
Pure functions, no I/O.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

VERDICTS = ("ok", "doubtful", "failed")
OK, DOUBTFUL, FAILED = VERDICTS


@dataclass(frozen=True)
class Finding:
    """One check: its name, its verdict and (unless ``ok``) the reason in words."""

    check: str
    verdict: str
    reason: str = ""

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {', '.join(VERDICTS)}, got {self.verdict!r}")
        if self.verdict != OK and not self.reason:
            raise ValueError(f"a {self.verdict} finding ({self.check}) needs a reason")


def graded(check: str, value: float, doubtful_above: float, failed_above: float, reason: str) -> Finding:
    """A finding from a measure where larger is worse: ``ok`` up to ``doubtful_above``,
    ``doubtful`` up to ``failed_above``, else ``failed``; ``reason`` is formatted with ``value``
    (``{value}``) when the finding is not ``ok``. A NaN value is ``doubtful`` (not measured)."""
    if value != value:  # NaN
        return Finding(check, DOUBTFUL, f"{check} could not be measured")
    if value <= doubtful_above:
        return Finding(check, OK)
    verdict = DOUBTFUL if value <= failed_above else FAILED
    return Finding(check, verdict, reason.format(value=value))


def worst(verdicts: Iterable[str]) -> str:
    """The worst of several verdicts (``ok`` for none)."""
    return max(verdicts, key=VERDICTS.index, default=OK)


@dataclass
class Verdict:
    """A result's verdict: the worst finding, the reasons (module docstring for their order) and,
    when the checks are named (the laser's), each check's verdict by name (``checks``)."""

    verdict: str = OK
    reasons: list[str] = field(default_factory=list)
    checks: dict[str, str] | None = None

    @classmethod
    def of(cls, findings: Iterable[Finding]) -> Verdict:
        """One pass of named checks: failed reasons first, each group in the order found."""
        found = list(findings)
        bad = sorted((f for f in found if f.verdict != OK), key=lambda f: -VERDICTS.index(f.verdict))
        return cls(worst(f.verdict for f in found), [f.reason for f in bad],
                   {f.check: f.verdict for f in found})

    @classmethod
    def from_json(cls, quality: Mapping[str, Any]) -> Verdict:
        """The verdict part of a ``quality`` object (its evidence is left out)."""
        checks = quality.get("checks")
        return cls(quality.get("verdict", OK), list(quality.get("reasons") or []),
                   None if checks is None else dict(checks))

    def doubt(self, reason: str, check: str | None = None) -> None:
        """A doubtful finding: its reason goes after the others."""
        self.reasons.append(reason)
        if self.verdict == OK:
            self.verdict = DOUBTFUL
        self._name(check, DOUBTFUL)

    def fail(self, reason: str, check: str | None = None) -> None:
        """A failed finding: its reason goes before every earlier one."""
        self.reasons.insert(0, reason)
        self.verdict = FAILED
        self._name(check, FAILED)

    def _name(self, check: str | None, verdict: str) -> None:
        if check is not None:
            self.checks = {**(self.checks or {}), check: verdict}

    def as_json(self) -> dict[str, Any]:
        """``{"verdict", "reasons"}``, and ``"checks"`` when the checks are named."""
        out: dict[str, Any] = {"verdict": self.verdict, "reasons": list(self.reasons)}
        if self.checks is not None:
            out["checks"] = dict(self.checks)
        return out


#: the evidence behind a verdict: what each check measured, by name. Its keys differ per check
#: and per pipeline (docs/reference/vision-json.md lists them), so it stays an open mapping of
#: JSON values (ADR 0034)
Evidence = Mapping[str, Any]


@dataclass(frozen=True)
class QualityReport:
    """A result's ``quality`` object: the :class:`Verdict` it came to (``verdict``, ``reasons``,
    ``checks`` when the checks are named) and the evidence the checks read. The JSON is
    ``{"verdict", "reasons", ["checks"], ...evidence}``."""

    verdict: str
    reasons: tuple[str, ...]
    checks: Mapping[str, str] | None
    evidence: Evidence

    @classmethod
    def of(cls, verdict: Verdict, evidence: Evidence) -> QualityReport:
        return cls(verdict.verdict, tuple(verdict.reasons), None if verdict.checks is None
                   else dict(verdict.checks), dict(evidence))

    @classmethod
    def from_json(cls, quality: Mapping[str, Any]) -> QualityReport:
        """From a ``quality`` object whose verdict keys come first (as every analysis writes it)."""
        head = [k for k in quality if k in ("verdict", "reasons", "checks")]
        if list(quality)[:len(head)] != head:
            raise ValueError(f"a quality object starts with its verdict, reasons and checks, got "
                             f"{list(quality)}")
        return cls.of(Verdict.from_json(quality), {k: v for k, v in quality.items() if k not in head})

    def as_verdict(self) -> Verdict:
        """A fresh :class:`Verdict` with the same verdict, reasons and checks (to add findings to)."""
        return Verdict(self.verdict, list(self.reasons), None if self.checks is None else dict(self.checks))

    def to_json(self) -> dict[str, Any]:
        return {**self.as_verdict().as_json(), **self.evidence}


def in_words(quality: Verdict | QualityReport) -> str:
    """The verdict as one sentence for the terminal: ``result ok`` or ``result doubtful: r1; r2``."""
    reasons = quality.reasons
    return f"result {quality.verdict}" + (": " + "; ".join(reasons) if reasons else "")


def describe(quality: Verdict | QualityReport) -> str:
    """The verdict as a list for the terminal: a head line and one line per reason."""
    if quality.verdict == OK:
        return "quality: ok (every check passed; numbers within the stated tolerances by their own scatter)"
    head = "quality: DOUBTFUL, check before use" if quality.verdict == DOUBTFUL else "quality: FAILED"
    return "\n".join([head, *(f"  - {r}" for r in quality.reasons)])


def rank(quality: Mapping[str, Any]) -> tuple[int, int]:
    """Order of two results of the same clip, better first: by verdict, and between equal verdicts
    by how many checks are not ``ok`` (a doubtful fit with one reason beats one with six)."""
    return VERDICTS.index(quality.get("verdict", OK)), len(quality.get("reasons") or [])
