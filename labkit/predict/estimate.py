"""One predicted number with how it was obtained, how accurate it is and what it cost."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

T = TypeVar("T")

CLOSED_FORM = "closed form"
STEADY_STATE = "steady-state solve"
SIMULATION = "simulation"


@dataclass(frozen=True)
class Estimate:
    """``value`` in ``unit``; ``accuracy`` is an absolute numerical error estimate in the same
    unit (None when the number is exact algebra), ``accuracy_how`` says how it was estimated;
    ``cost_s`` is wall time. Model limits (point dipoles) are in ``note``, not in ``accuracy``."""

    key: str
    label: str
    value: float | str | bool | None
    unit: str
    method: str
    equation: str = ""
    accuracy: float | None = None
    accuracy_how: str = ""
    cost_s: float = 0.0
    note: str = ""

    def to_json(self) -> dict:
        value = self.value
        if isinstance(value, float) and not math.isfinite(value):
            value = None
        acc = self.accuracy if self.accuracy is None or math.isfinite(self.accuracy) else None
        return {"value": value, "unit": self.unit, "method": self.method, "equation": self.equation,
                "accuracy": acc, "accuracy_how": self.accuracy_how, "cost_s": self.cost_s,
                "note": self.note, "label": self.label}


def timed(fn: Callable[[], T]) -> tuple[T, float]:
    """Call ``fn`` and return its result with the wall time it took (s)."""
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0
