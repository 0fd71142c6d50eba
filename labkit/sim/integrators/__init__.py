"""Integrators for compiled scenes.

* ``auto`` (default): the composition and step chosen per scene by :func:`auto_composition`
  (``splitting4`` for a driven body, ``kahanli8`` for interacting free bodies);
* ``splitting4`` (Suzuki 5-stage order 4), ``yoshida4``, ``yoshida6``, ``kahanli6``, ``kahanli8``,
  ``strang``: fixed step ``h = T/N`` kick-rotate-kick splittings with exact free rotation (numba, cached);
* ``dop853``, ``radau``, ``lsoda``: :func:`scipy.integrate.solve_ivp` references with
  per-component (scaled) tolerances;
* ``cyrk-dop853``: the same DOP853 compiled (CyRK's C++ solver with a numba right-hand side),
  the fair peer of ``labkit bench sim``.

Every integrator returns a :class:`RawRun`; :func:`labkit.sim.run.simulate` turns it into a
:class:`labkit.sim.result.SimResult` with invariants, status and quantities of interest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from labkit.errors import LabkitError

if TYPE_CHECKING:  # annotations only: `labkit simulate --help` reads the names below without numpy
    import numpy as np

SPLITTINGS = {
    "auto": "auto",
    "splitting4": "suzuki4",
    "suzuki4": "suzuki4",
    "yoshida4": "yoshida4",
    "yoshida6": "yoshida6",
    "kahanli6": "kahanli6",
    "yoshida8": "yoshida8",
    "kahanli8": "kahanli8",
    "strang": "strang",
}
REFERENCES = {"dop853": "DOP853", "radau": "Radau", "lsoda": "LSODA"}
#: compiled peers (CyRK's C++ solver, numba right-hand side; the optional ``bench`` extra)
COMPILED = {"cyrk-dop853": "DOP853"}
INTEGRATORS = sorted(set(SPLITTINGS) | set(REFERENCES) | set(COMPILED))
DEFAULT_INTEGRATOR = "auto"
MAX_SAMPLE_BYTES = 1 << 30


class SimulationError(LabkitError):
    """A simulation cannot run as asked (unknown integrator, horizon too long for memory, ...)."""


@dataclass
class RawRun:
    """What an integrator returns: samples of the (principal-frame) state and how it ended."""

    integrator: str
    setting: dict
    status: int  # 0 ok, 1 nan, 2 blowup, 3 contact, 4 escape, 5 solver failed
    event_time: float
    n_force: int
    t: np.ndarray
    x: np.ndarray | None = None  # (n, nb, 3)
    v: np.ndarray | None = None
    R: np.ndarray | None = None  # (n, nb, 3, 3), principal frame -> lab
    L: np.ndarray | None = None  # (n, nb, 3), lab angular momentum
    y: np.ndarray | None = None  # reduced angle (n,)
    yd: np.ndarray | None = None  # reduced rate (n,)
    impulse: np.ndarray | None = None  # (nb, 3) time integral of magnetic force
    budget: np.ndarray | None = None  # (n,) damping's accumulated change of E - wz J_z
    message: str = ""
    extra: dict = field(default_factory=dict)


def auto_composition(body_pairs: bool) -> tuple[str, str]:
    """(composition, integrator name) that ``auto`` runs for a scene.

    Interacting free bodies (``mbs_fig6_1``) take Kahan and Li's order-8 composition: over 1e4
    cycles its energy drift is 4.3e-13 at 32 steps per period (544 force evaluations per period)
    where ``splitting4`` at 128 steps (640 evaluations) drifts 4.3e-11 (``labkit bench sim``,
    docs/reference/simulator.md). A driven body keeps ``splitting4``, whose drift there is already ~1e-13."""
    return ("kahanli8", "kahanli8") if body_pairs else ("suzuki4", "splitting4")


def auto_steps_per_period(omega: float, omega_max: float, order: int, multiple: int = 1,
                          body_pairs: bool = False) -> int:
    """Steps per drive period: ``N >= 64`` (order >= 4; 256 for Strang) and ``h omega_max <= 0.5``,
    rounded up to a multiple of ``multiple`` (so samples fall on exact multiples of T/multiple).

    Scenes with interacting free bodies take ``N >= 128`` with an order-4 or order-6 composition
    (at 64 the two-body energy error of ``mbs_fig6_1`` is 7e-10 after 1e4 cycles, bounded; at 128
    it is 4e-11) and ``N >= 32`` with an order-8 one (4.3e-13, :func:`auto_composition`)."""
    if order < 4:
        n_min = 256
    elif body_pairs:
        n_min = 32 if order >= 8 else 128
    else:
        n_min = 64
    n = max(n_min, math.ceil(2.0 * math.pi * omega_max / (0.5 * omega))) if omega > 0 else n_min
    return int(math.ceil(n / multiple) * multiple)


def check_memory(n_samples: int, nb: int) -> None:
    size = n_samples * max(nb, 1) * 18 * 8
    if size > MAX_SAMPLE_BYTES:
        raise SimulationError(
            f"{n_samples} samples of {nb} bodies need {size / 2**30:.1f} GiB: "
            "lower --cycles or the samples per period"
        )


def get_integrator(name: str):
    """Look up an integrator's run function by name."""
    key = name.lower()  # each family imported when asked for (scipy only for its references)
    if key in SPLITTINGS:
        from labkit.sim.integrators import splitting_run

        return lambda system, cycles, **kw: splitting_run.run(system, cycles, SPLITTINGS[key], name=key, **kw)
    if key in REFERENCES:
        from labkit.sim.integrators import reference

        return lambda system, cycles, **kw: reference.run(system, cycles, REFERENCES[key], name=key, **kw)
    if key in COMPILED:
        from labkit.sim.integrators import compiled_reference

        method = COMPILED[key]
        return lambda system, cycles, **kw: compiled_reference.run(system, cycles, method, name=key, **kw)
    raise SimulationError(f"unknown integrator {name!r} (choose from {', '.join(INTEGRATORS)})")
