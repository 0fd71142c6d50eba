"""Bad input to the numerics tools, caught before any work is done, with a clear message.

* a tolerance or a step count that cannot reach the requested accuracy;
* a horizon whose samples do not fit in memory;
* (sweeps) a scheduler that does not answer: see :mod:`labkit.numerics.sweep`.
"""

from __future__ import annotations

import math

from labkit.errors import LabkitError

EPS = 2.220446049250313e-16
MIN_RTOL = 1e-14  # below this DOP853 cannot deliver the tolerance in double precision
MAX_H_OMEGA = 2.0  # a kick-drift-kick splitting is unstable beyond h * omega_max = 2 (linear theory)
DEFAULT_MEMORY_BYTES = 1 << 30


class NumericsError(LabkitError):
    """A numerics request cannot be met as asked (the message says why and what to change)."""


def check_rtol(rtol: float, target_error: float | None = None) -> None:
    """Refuse a relative tolerance that double precision cannot deliver, or one looser than the
    requested error (an adaptive method then cannot be expected to reach it)."""
    if not (rtol > 0 and math.isfinite(rtol)):
        raise NumericsError(f"rtol {rtol!r} must be a positive number")
    if rtol < MIN_RTOL:
        raise NumericsError(
            f"rtol {rtol:g} is below what double precision can deliver ({MIN_RTOL:g}): "
            "use a tighter reference only through a higher-order fixed-step method"
        )
    if target_error is not None and rtol > target_error:
        raise NumericsError(
            f"rtol {rtol:g} cannot reach the requested error {target_error:g}: use rtol <= {target_error:g}"
        )


def check_steps(
    steps_per_period: int,
    omega: float,
    omega_max: float,
    order: int = 4,
    target_error: float | None = None,
    cycles: float = 1.0,
) -> None:
    """Refuse a step count that makes the splitting unstable (``h omega_max > 2``) or whose
    error bound ``C (h omega_max)^order`` per period, or round-off ``cycles N eps``, exceeds
    ``target_error`` (``C = 1`` is a rough, optimistic constant: it rejects only hopeless settings)."""
    if steps_per_period <= 0:
        raise NumericsError(f"steps per period {steps_per_period} must be positive")
    h_omega = 2.0 * math.pi * omega_max / (omega * steps_per_period)
    if h_omega > MAX_H_OMEGA:
        need = math.ceil(2.0 * math.pi * omega_max / (omega * MAX_H_OMEGA))
        raise NumericsError(
            f"{steps_per_period} steps per period give h * omega_max = {h_omega:.3g} > {MAX_H_OMEGA:g}: "
            f"the splitting is unstable; use at least {need} steps per period"
        )
    if target_error is None:
        return
    truncation = cycles * h_omega**order
    roundoff = cycles * steps_per_period * EPS
    if roundoff > target_error:
        raise NumericsError(
            f"{cycles:g} cycles x {steps_per_period} steps accumulate round-off ~{roundoff:.2g} > "
            f"the requested error {target_error:g}: no step count reaches it in double precision"
        )
    if truncation > 1e3 * target_error:
        raise NumericsError(
            f"{steps_per_period} steps per period (h * omega_max = {h_omega:.3g}, order {order}) "
            f"give an error ~{truncation:.2g} over {cycles:g} cycles, far above the requested "
            f"{target_error:g}: use more steps per period"
        )


def check_horizon(
    cycles: float, samples_per_period: int, bodies: int, limit_bytes: int = DEFAULT_MEMORY_BYTES
) -> int:
    """Bytes the stored samples need; refuse a horizon that does not fit in ``limit_bytes``."""
    if not (cycles > 0 and math.isfinite(cycles)):
        raise NumericsError(f"horizon of {cycles!r} cycles must be a positive number")
    n = int(cycles * samples_per_period) + 2
    size = n * max(bodies, 1) * 18 * 8
    if size > limit_bytes:
        fit = int(limit_bytes / (max(bodies, 1) * 18 * 8 * samples_per_period))
        raise NumericsError(
            f"{cycles:g} cycles at {samples_per_period} samples per period need "
            f"{size / 2**30:.1f} GiB for the samples (limit {limit_bytes / 2**30:.1f} GiB): "
            f"use at most {fit} cycles or fewer samples per period"
        )
    return size
