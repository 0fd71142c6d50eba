"""Stress cases of docs/reference/bench-sim.md, each run with the simulator's default integrator
(splitting4, automatic step) and judged by its pass criterion, printed as met or not met.

Every case has a descriptive name (``conical-exact``, ``two-body-bound-state``, ...) and keeps
its number from docs/reference/bench-sim.md#stress-cases (``S1`` ... ``S11``) as an alias: both are printed,
and ``labkit bench sim --stress`` takes either. The cases live in :mod:`labkit.numerics.stress_cases`.

A case that raises is a verdict with ``met = False`` and the error as its detail: a failing
case is shown, never dropped. Horizons are shorter with ``quick`` (and ``smoke``); where a criterion is stated
"after 1e4 cycles" and the run is shorter, the measured error is extrapolated linearly (the
growth of a phase error under a symplectic splitting, Hairer 1997) and the text says so.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from labkit.numerics.stress_cases.bodies import s5, s6, s7, s8, s9
from labkit.numerics.stress_cases.common import (
    I_S1,
    LEVELS,
    OMEGA_S1,
    TAU_C_S1,
    TAU_S_S1,
    Verdict,
    conical_dict,
    conical_scene,
    fig5_13_dict,
    s1_like,
)
from labkit.numerics.stress_cases.conical import s1, s2, s3, s4, s10, s11

CASES: dict[str, Callable[[str], Verdict]] = {
    "S1": s1,
    "S2": s2,
    "S3": s3,
    "S4": s4,
    "S5": s5,
    "S6": s6,
    "S7": s7,
    "S8": s8,
    "S9": s9,
    "S10": s10,
    "S11": s11,
}

#: descriptive name of each case (its S-number stays as an alias)
NAMES: dict[str, str] = {
    "S1": "conical-exact",
    "S2": "tiny-inertia-si-units",
    "S3": "cone-angle-singularity",
    "S4": "stiff-internal-frequency",
    "S5": "unequal-inertia-fig5_7",
    "S6": "off-axis-equilibrium-fig5_4",
    "S7": "two-body-bound-state",
    "S8": "contact-event",
    "S9": "escape-event",
    "S10": "frequency-sweep",
    "S11": "rotational-damping",
}
ALIASES: dict[str, str] = {name: case_id for case_id, name in NAMES.items()}

__all__ = [
    "ALIASES", "CASES", "I_S1", "LEVELS", "NAMES", "OMEGA_S1", "TAU_C_S1", "TAU_S_S1", "Verdict",
    "case_id", "conical_dict", "conical_scene", "fig5_13_dict", "run_case", "run_stress_cases", "s1_like",
]


def case_id(key: str) -> str | None:
    """``S7`` for ``S7``, ``s7`` or ``two-body-bound-state``; None for an unknown case."""
    k = key.strip()
    if k.upper() in CASES:
        return k.upper()
    return ALIASES.get(k.lower())


def run_case(case_id: str, level: str = "quick") -> Verdict:
    """Run one case; an exception becomes a not-met verdict that says what went wrong."""
    fn = CASES[case_id]
    start = time.perf_counter()
    try:
        verdict = fn(level)
    except Exception as exc:  # noqa: BLE001 - a failing case is shown, never dropped
        verdict = Verdict(
            case_id,
            (fn.__doc__ or case_id).strip().splitlines()[0],
            "",
            False,
            {},
            0.0,
            time.perf_counter() - start,
            f"raised {type(exc).__name__}: {exc}",
        )
    verdict.name = NAMES[case_id]
    return verdict


def run_stress_cases(
    quick: bool = True, only: list[str] | None = None, progress=None, level: str | None = None
) -> list[Verdict]:
    """Every case (or ``only`` those, by S-number or name), in order; one verdict each.

    ``level`` (``smoke``, ``quick``, ``full``) overrides ``quick``; ``smoke`` is for tests: the
    same cases and criteria on very short horizons.
    """
    level = level or ("quick" if quick else "full")
    wanted = None if not only else {case_id(k) or k for k in only}
    out = []
    for cid in CASES:
        if wanted and cid not in wanted:
            continue
        out.append(run_case(cid, level))
        if progress is not None:
            progress(out[-1])
    return out
