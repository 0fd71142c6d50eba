"""Flash times against the rotor pulse train, both in CPU cycles of the simulated ATmega328P
(one Timer1 tick at prescaler 1): pure functions used by test_strobe_firmware.py.

A flash at cycle r between rotor edges e_k <= r < e_{k+1} sees the rotor at position
k + (r - e_k) / (e_{k+1} - e_k) revolutions. The apparent angle is that position's fraction;
unwrapped, it grows at the apparent frequency (Hz) the strobe was commanded. The jitter is
what is left of the flash times after a straight line through the unwrapped apparent angle
against time, converted back to ticks with the local period.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CYCLES_PER_S = 16e6


@dataclass(frozen=True)
class FlashFit:
    """The straight line through the apparent angle of ``n`` flashes."""

    n: int
    apparent_hz: float
    jitter_ticks: float          # largest |residual| in timer ticks
    residual_rms_ticks: float
    worst_cycle: int             # the flash with the largest residual
    worst_position: float        # its rotor position (revolutions)


def rotor_positions(edges: list[int], flash_starts: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(flash cycle, rotor position in revolutions, local period in cycles) for every flash
    that lies between two edges."""
    e = np.asarray(edges, dtype=np.int64)
    r = np.asarray(flash_starts, dtype=np.int64)
    k = np.searchsorted(e, r, side="right") - 1
    inside = (k >= 0) & (k + 1 < len(e))
    k, r = k[inside], r[inside]
    period = (e[k + 1] - e[k]).astype(float)
    position = k + (r - e[k]) / period
    return r, position, period


def fit_flashes(edges: list[int], flash_starts: list[int]) -> FlashFit:
    """Apparent frequency and jitter of the flashes (at least 3) against the edges."""
    t_cycles, position, period = rotor_positions(edges, flash_starts)
    if len(t_cycles) < 3:
        raise ValueError(f"only {len(t_cycles)} flashes between rotor edges")
    angle = np.unwrap(np.mod(position, 1.0) * 2 * np.pi) / (2 * np.pi)
    t = (t_cycles - t_cycles[0]) / CYCLES_PER_S
    design = np.vstack([t, np.ones_like(t)]).T
    coef, *_ = np.linalg.lstsq(design, angle, rcond=None)
    residual_ticks = (angle - design @ coef) * period
    worst = int(np.argmax(np.abs(residual_ticks)))
    return FlashFit(len(t), float(coef[0]), float(np.abs(residual_ticks[worst])),
                    float(np.sqrt(np.mean(residual_ticks ** 2))), int(t_cycles[worst]),
                    float(position[worst]))


def flashes_between(oc1a: list[tuple[int, int]], start: int, end: int) -> list[int]:
    """Rising-edge cycles of the flashes in [start, end)."""
    return [rise for rise, _fall in oc1a if start <= rise < end]
