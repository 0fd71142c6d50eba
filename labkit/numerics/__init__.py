"""labkit.numerics: error against run time, stress cases, fast kernels and sweeps for labkit.sim.

Public interface::

    from labkit.numerics import work_precision, reference, run_stress_cases, Ladder
    report = work_precision("conical_5_1", cycles=20, ladder=Ladder.quick())
    verdicts = run_stress_cases(quick=True)          # S1-S11, each met / not met
    # (the stress cases: docs/reference/bench-sim.md#stress-cases)

Sweeps (stability maps) live in :mod:`labkit.numerics.sweep`; the batch kernels in
:mod:`labkit.numerics.kernels`. ``labkit bench sim`` and ``labkit sweep`` are the commands.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from labkit.lazy import lazy_attributes

#: where each public name lives; imported on first use (PEP 562) so that importing
#: ``labkit.numerics.checks`` (argument checks of ``labkit sweep``) does not load numba and scipy.
_HOME = {
    **{name: "labkit.numerics.checks" for name in (
        "NumericsError", "check_horizon", "check_rtol", "check_steps")},
    **{name: "labkit.numerics.workprecision" for name in (
        "TARGETS", "Ladder", "Point", "Reference", "SceneReport", "reference", "require_target",
        "speedup_at_equal_error", "work_precision")},
}

if TYPE_CHECKING:  # pragma: no cover
    from labkit.numerics.checks import NumericsError, check_horizon, check_rtol, check_steps
    from labkit.numerics.workprecision import (
        TARGETS,
        Ladder,
        Point,
        Reference,
        SceneReport,
        reference,
        require_target,
        speedup_at_equal_error,
        work_precision,
    )


__getattr__ = lazy_attributes(__name__, _HOME)


__all__ = [
    "TARGETS",
    "Ladder",
    "NumericsError",
    "Point",
    "Reference",
    "SceneReport",
    "check_horizon",
    "check_rtol",
    "check_steps",
    "reference",
    "require_target",
    "speedup_at_equal_error",
    "work_precision",
]
