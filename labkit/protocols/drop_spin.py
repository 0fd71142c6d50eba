"""The floator's spin at the instant it drops, from a sampled tachometer (Fig. 6.18, Eq. 6.37).

A tachometer sends a line every 0.1 s or so, and the floator is still spinning up when it
drops (Sec. 6.5), so the last line before the drop was taken up to a line spacing (plus
the balance's reporting delay) *before* the drop: registering it as "the spin at the drop"
reads low by (spin-up rate) x (that delay), 1-9 rad/s on the emulated Fig. 6.18 rig. That
pushed the fitted C of Eq. 6.37 up by 1-1.5 %, outside its 95 % interval, because
``C = (w - v) w / (1 - w/w_ref)`` depends on the small difference ``w - v``.

These pure functions remove that bias: the drop instant is bracketed by the balance (last
reading that saw the floator held, first that saw it gone) and by the spin tachometer (no
fresh line after its last one for one line spacing), and a straight line through the last
``fit_window_s`` of spin readings (each taken at its arrival time: a period-measuring
tachometer such as ``labkit_tach`` reports nearly the latest speed) is evaluated at the
drop instant.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence


def fresh_samples(samples: Sequence[tuple[float, float]], min_value: float) -> list[tuple[float, float]]:
    """``(t, value)`` pairs that carry new information: finite, above ``min_value``, and not an
    exact repeat of the previous value (a tachometer holding its display after its target
    is gone repeats the last line)."""
    out: list[tuple[float, float]] = []
    previous: float | None = None
    for t, value in samples:
        if math.isfinite(value) and value > min_value and value != previous:
            out.append((t, value))
        previous = value
    return out


def line_spacing(times: Sequence[float]) -> float:
    """Median interval between successive lines (s); 0 with fewer than two lines."""
    gaps = [b - a for a, b in zip(times, times[1:], strict=False) if b > a]
    return statistics.median(gaps) if gaps else 0.0


def drop_instant(last_held_t: float, gone_t: float | None, last_spin_t: float, spacing_s: float) -> float:
    """Best estimate of when the floator dropped (s).

    The balance brackets it between ``last_held_t`` (last reading that saw the floator)
    and ``gone_t`` (first that did not; None if the balance has not seen it go): the
    midpoint. The spin tachometer's last fresh line (at ``last_spin_t``) bounds it: after
    that line's window started (``- spacing_s``), and before the next line was due
    (``+ spacing_s``), since a target still there would have produced a fresh line.
    """
    estimate = last_held_t if gone_t is None else 0.5 * (last_held_t + gone_t)
    if spacing_s > 0:
        estimate = min(estimate, last_spin_t + spacing_s)
    return max(estimate, last_spin_t - spacing_s)


def spin_at(samples: Sequence[tuple[float, float]], t_drop: float, fit_window_s: float = 0.5) -> float:
    """Spin (same unit as the values) at ``t_drop`` from window-mean tachometer lines.

    ``samples`` are ``(arrival time, value)`` in time order, already filtered by
    :func:`fresh_samples`. A least-squares line through the samples within ``fit_window_s``
    of the last one (at least three) is evaluated at ``t_drop``. With fewer than two
    samples the last value is returned.
    """
    if not samples:
        raise ValueError("no spin readings before the drop")
    if len(samples) < 2:
        return samples[-1][1]
    last_t = samples[-1][0]
    use = [s for s in samples if s[0] >= last_t - fit_window_s]
    if len(use) < 3:
        use = list(samples[-3:])
    tm = statistics.fmean(t for t, _ in use)
    vm = statistics.fmean(v for _, v in use)
    sxx = sum((t - tm) ** 2 for t, _ in use)
    if sxx <= 0:
        return samples[-1][1]
    slope = sum((t - tm) * (v - vm) for t, v in use) / sxx
    return vm + slope * (t_drop - tm)
