"""One range syntax for every option that takes a list of numbers (``--set``, ``--map``,
``--ratios``, ``--k``; docs/reference/command-grammar.md):

* ``START:STOP:step=S``  START, START+S, ... up to STOP (STOP included when a step lands on it)
* ``START:STOP:n=N``     N evenly spaced values, both ends included
* ``A,B,C``              the values as written; ``X`` one value

The old bare spelling ``START:STOP:C`` meant a step in ``--set`` and a count in ``--map`` and
``--ratios``. It still works where its meaning was always the step (``--set``, ``bare="step"``);
elsewhere (``bare="error"``) it is refused with the new spelling. The number of values is
computed before any list is built and refused above ``limit``. Pure functions, no I/O.
"""

from __future__ import annotations

import math
from typing import Literal

Bare = Literal["step", "error"]


class RangeError(ValueError):
    """A range that cannot be used; the message says why (without the option's name)."""


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise RangeError(f"{what} {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise RangeError(f"{what} {text.strip()!r} is not a finite number")
    return value


def _fmt(x: float) -> str:
    return f"{x:g}"


def range_count(start: float, stop: float, step: float) -> int:
    """How many values ``START:STOP:step=S`` gives (RangeError if the step does not go there)."""
    if step == 0 or (stop - start) / step < 0:
        raise RangeError(f"step {_fmt(step)} does not go from {_fmt(start)} to {_fmt(stop)}")
    return int(math.floor((stop - start) / step + 1e-9)) + 1


def parse_range(text: str, *, bare: Bare = "error", limit: int = 10_000) -> list[float]:
    """The values of a range, list or single number (see the module docstring)."""
    text = text.strip()
    if ":" not in text:
        items = [p for p in text.replace(";", ",").split(",") if p.strip()]
        if not items:
            raise RangeError("no values")
        if len(items) > limit:
            raise RangeError(f"gives {len(items)} values, more than the limit of {limit}")
        return [_number(p, "value") for p in items]
    parts = text.split(":")
    if len(parts) != 3:
        raise RangeError(f"{text!r}: a range is start:stop:step=S or start:stop:n=N")
    start, stop = _number(parts[0], "start"), _number(parts[1], "stop")
    key, sep, value = parts[2].partition("=")
    key = key.strip().lower()
    if not sep:
        third = _number(parts[2], "third part")
        if bare == "error":
            count = f"{third:.0f}" if third == int(third) else _fmt(third)
            raise RangeError(f"{text!r} is ambiguous: write {_fmt(start)}:{_fmt(stop)}:n={count} for "
                             f"{count} values or {_fmt(start)}:{_fmt(stop)}:step={_fmt(third)} for a step")
        key, value = "step", parts[2]
    if key == "step":
        step = _number(value, "step")
        n = range_count(start, stop, step)
        if n > limit:
            raise RangeError(f"gives {n} values, more than the limit of {limit}")
        return [start + i * step for i in range(n)]
    if key == "n":
        n_value = _number(value, "n")
        if n_value < 1 or n_value != int(n_value):
            raise RangeError(f"n={value.strip()} must be a whole number >= 1")
        if n_value > limit:
            raise RangeError(f"gives {n_value:.0f} values, more than the limit of {limit}")
        n = int(n_value)
        if n == 1:
            return [start]
        return [start + (stop - start) * k / (n - 1) for k in range(n)]
    raise RangeError(f"{text!r}: the third part is step=S or n=N, got {parts[2].strip()!r}")
