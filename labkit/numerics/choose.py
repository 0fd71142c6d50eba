"""Method and step count for a requested error (``labkit simulate --target-error``).

For each candidate composition (order 4, 6 and 8; all symplectic, so the invariant stays
bounded whichever is chosen) a short pilot run estimates the error constant: the run at ``N``
and at ``2N`` steps per period over a few cycles give ``e(N) ~ |y_N - y_2N| 2^p / (2^p - 1)``
(Richardson) in the stroboscopic error of docs/reference/bench-sim.md. A splitting's phase error grows
linearly with time, so over ``C`` cycles ``e ~ K C N^-p``; the step count that reaches the
target is ``N = N_pilot (e_C(N_pilot) / target)^(1/p)`` with a safety factor, and the method
with the fewest force evaluations (stages x N) is chosen. The estimate is printed with the run;
a pilot outside the asymptotic range (observed order far from ``p``) is refined first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from labkit.numerics import metrics
from labkit.numerics.checks import NumericsError
from labkit.sim import CompiledSystem, Scene, simulate
from labkit.sim.integrators import SPLITTINGS
from labkit.sim.integrators.splitting import COMPOSITIONS

CANDIDATES = ("splitting4", "kahanli6", "kahanli8")
PILOT_CYCLES = 4.0
SAFETY = 2.0  # aim this much below the target
ROUND_OFF = 1e-15  # per step (~1e-10 after 50 cycles of 2048 steps, docs/reference/bench-sim.md)


@dataclass
class Choice:
    """The chosen integrator and steps per period, and what the pilots estimated."""

    integrator: str
    steps_per_period: int
    estimated_error: float
    force_evals_per_period: int
    pilots: dict

    def line(self) -> str:
        return (f"chose {self.integrator} N={self.steps_per_period} ({self.force_evals_per_period} force "
                f"evaluations per period): estimated error {self.estimated_error:.2g} "
                f"(pilot over {PILOT_CYCLES:g} cycles, Richardson, linear growth)")


def _pilot_error(scene: Scene, system: CompiledSystem, integrator: str, n: int, cycles: float) -> float:
    kw = {"system": system, "samples_per_period": 1, "drift_threshold": math.inf,
          "rotation_threshold": math.inf}
    a = simulate(scene, cycles, integrator, steps_per_period=n, **kw)
    b = simulate(scene, cycles, integrator, steps_per_period=2 * n, **kw)
    if a.status != "ok" or b.status != "ok":
        return math.nan
    moments = [body.moment_Am2 for body in scene.bodies]
    return metrics.state_errors(a, b, system.length_scale, system.omega, moments).final


def _estimate(scene: Scene, system: CompiledSystem, integrator: str, cycles: float) -> tuple[int, float, int]:
    """(pilot N, error at N over the pilot, refinements) for one composition, in its asymptotic range."""
    order = COMPOSITIONS[SPLITTINGS[integrator]][1]
    n = 16 if order >= 6 else 32
    previous = None
    for _ in range(5):
        diff = _pilot_error(scene, system, integrator, n, cycles)
        if not math.isfinite(diff):
            n *= 2
            continue
        err = diff * 2**order / (2**order - 1)
        if previous is not None and previous[1] > 0 and err > 0:
            observed = math.log2(previous[1] / err)
            if abs(observed - order) < 1.0 or err < 1e-12:
                return n, err, 0
        previous = (n, err)
        n *= 2
    if previous is None:
        raise NumericsError(f"{integrator}: the pilot runs failed; the scene may be unstable")
    return previous[0], previous[1], 1


def choose(scene: Scene, system: CompiledSystem, cycles: float, target: float,
           samples_per_period: int = 1, candidates: tuple[str, ...] = CANDIDATES) -> Choice:
    """The cheapest composition and steps per period reaching ``target`` over ``cycles``."""
    if system.kind != "rigid":
        raise NumericsError(f"--target-error chooses among rigid-body splittings; {scene.name} compiles to "
                            f"{system.kind}: give --integrator and --steps-per-period instead")
    pilot_cycles = min(PILOT_CYCLES, cycles)
    best: Choice | None = None
    pilots = {}
    for name in candidates:
        weights, order = COMPOSITIONS[SPLITTINGS[name]]
        n0, err0, _ = _estimate(scene, system, name, pilot_cycles)
        grown = err0 * cycles / pilot_cycles
        n = max(n0 * (SAFETY * grown / target) ** (1.0 / order), 8.0)
        n = int(math.ceil(n / samples_per_period) * samples_per_period)
        estimate = grown * (n0 / n) ** order
        pilots[name] = {"pilot_steps": n0, "pilot_error": err0, "steps": n, "estimated_error": estimate}
        cost = len(weights) * n
        if best is None or cost < best.force_evals_per_period:
            best = Choice(name, n, estimate, cost, pilots)
    assert best is not None
    round_off = ROUND_OFF * cycles * best.steps_per_period
    if target < round_off:
        raise NumericsError(
            f"target error {target:g} over {cycles:g} cycles is below the round-off of "
            f"{best.steps_per_period} steps per period (~{round_off:.1g}): ask for more or fewer cycles"
        )
    best.pilots = pilots
    return best
