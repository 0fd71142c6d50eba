"""Argument types for numeric command-line options: finite, in range, with the unit in the words.

``type=number(low=0, low_open=True)`` refuses ``nan``, ``inf``, ``-1`` and ``0`` as one
argparse error line (``argument --cycles: must be a finite number > 0, got nan``), exit 2,
instead of a traceback deep in the work. :func:`check_number` is the same test as a pure
function (hypothesis-fuzzed in tests/cli/test_option_numbers.py).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def check_number(text: str, low: float | None = None, high: float | None = None, low_open: bool = False,
                 integer: bool = False, why: str = "") -> float | int:
    """``text`` as a number within [low, high] (``low_open``: > low); ValueError in words otherwise."""
    kind = "a whole number" if integer else "a finite number"
    bounds = []
    if low is not None:
        bounds.append(f"{'>' if low_open else '>='} {low:g}")
    if high is not None:
        bounds.append(f"<= {high:g}")
    want = f"must be {kind}" + (f" {' and '.join(bounds)}" if bounds else "") + (f" ({why})" if why else "")
    try:
        value: float | int = int(text, 10) if integer else float(text)
    except ValueError:
        raise ValueError(f"{want}, got {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{want}, got {text}")
    if low is not None and (value < low or (low_open and value == low)):
        raise ValueError(f"{want}, got {text}")
    if high is not None and value > high:
        raise ValueError(f"{want}, got {text}")
    return value


def number(low: float | None = None, high: float | None = None, low_open: bool = False,
           integer: bool = False, why: str = "") -> Callable[[str], float | int]:
    """An argparse ``type=`` that applies :func:`check_number`."""

    def parse(text: str) -> float | int:
        try:
            return check_number(text, low, high, low_open, integer, why)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = "whole number" if integer else "number"  # argparse names the type in errors
    return parse
