"""Which version of an image analysis made a session's numbers, and how closely two versions are
stated to agree (docs/explanation/replay.md#analysis-versions,
docs/decisions/0040-analysis-versions-and-the-laser-speed.md).

Each pipeline declares its :class:`AnalysisVersion` beside its code
(:mod:`labkit.vision.laser.version`, :mod:`labkit.vision.strobe.version`): a number bumped
whenever the analysis's answers may change, and its :class:`Accuracy` per quantity. A session
records the versions it was analysed with (``run.json``'s ``analyses``); a replay by the same
version compares the numbers within relative 1e-6 (the same analysis of the same bytes, only
the CPU's rounding may differ), one by another version within the accuracy stated here.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TypeGuard

#: a session whose run.json names no version of an analysis was made by its first version
FIRST_VERSION = 1
_NUMBER = re.compile(r"[-+]?\d[\d.,e+-]*")


@dataclass(frozen=True)
class Accuracy:
    """How closely one quantity of an analysis is stated to be right: two answers agree when they
    differ by at most ``rel`` of the larger value or ``abs`` (in the quantity's unit), whichever
    is larger; with ``of_other`` the tolerance is ``rel`` of another value of the same result
    (a standard error from two halves moves with each half's angle, not with its own size);
    ``words_only``: a text (a verdict's reasons) compared without its numbers; neither: equal."""

    words: str
    rel: float = 0.0
    abs: float = 0.0
    of_other: bool = False
    words_only: bool = False

    def agrees(self, a: object, b: object, other: float | None = None) -> bool:
        """Whether two answers agree within this accuracy (``other``: the value ``of_other``
        refers to, the larger of the two results')."""
        if self.words_only:
            return _masked(a) == _masked(b)
        if not (is_number(a) and is_number(b)):
            return a == b
        x, y = float(a), float(b)
        if math.isnan(x) and math.isnan(y):
            return True
        scale = abs(other) if self.of_other and other is not None else max(abs(x), abs(y))
        return abs(x - y) <= max(self.rel * scale, self.abs) + 1e-15


@dataclass(frozen=True)
class AnalysisVersion:
    """An image analysis's name, version and stated accuracy per quantity."""

    name: str
    version: int
    accuracy: Mapping[str, Accuracy]

    def describe(self) -> str:
        """The accuracy table in one line, e.g. ``tilt 1 %, centre 0.5 px, verdict equal``."""
        return ", ".join(f"{quantity} {acc.words}" for quantity, acc in self.accuracy.items())


def is_number(value: object) -> TypeGuard[int | float]:
    """An int or a float, not a bool (JSON numbers as results hold them)."""
    return isinstance(value, int | float) and not isinstance(value, bool)


def _masked(value: object) -> object:
    """A text, or a list of texts, with every number replaced by ``#``."""
    if isinstance(value, str):
        return _NUMBER.sub("#", value)
    if isinstance(value, list):
        return [_masked(v) for v in value]
    return value
