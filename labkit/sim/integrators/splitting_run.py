"""Drive the numba splitting kernels for a compiled system (allocation, step rule, samples)."""

from __future__ import annotations

import math

import numpy as np

from labkit.sim.compile import CompiledSystem
from labkit.sim.integrators.raw_run import RawRun, SimulationError, check_memory
from labkit.sim.integrators.shapes import run_fixed_top, run_free_pair, scene_shape, stage_turns
from labkit.sim.integrators.splitting import COMPOSITIONS, run_reduced, run_rigid


def auto_composition(body_pairs: bool) -> tuple[str, str]:
    """(composition, integrator name) that ``auto`` runs for a scene.

    Interacting free bodies (``mbs_fig6_1``) take Kahan and Li's order-8 composition: over 1e4
    cycles its energy drift is 4.3e-13 at 32 steps per period (544 force evaluations per period)
    where ``splitting4`` at 128 steps (640 evaluations) drifts 4.3e-11 (``labkit bench sim``,
    docs/reference/simulator.md). A driven body keeps ``splitting4``, whose drift there is
    already ~1e-13."""
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


def run(
    system: CompiledSystem,
    cycles: float,
    composition: str,
    name: str,
    steps_per_period: int | None = None,
    samples_per_period: int = 8,
    t0: float = 0.0,
    decimate: int = 1,
    **_: object,
) -> RawRun:
    """Integrate ``cycles`` drive periods with ``h = T / steps_per_period`` (automatic if None);
    ``composition`` "auto" is chosen per scene (:func:`auto_composition`)."""
    body_pairs = system.kind == "rigid" and system.flags is not None and bool(system.flags[2])
    chosen_by = None
    if composition == "auto":
        composition, name = auto_composition(body_pairs)
        chosen_by = "auto: " + ("interacting free bodies" if body_pairs else "one driven body or none")
    weights, order = COMPOSITIONS[composition]
    if steps_per_period is None:
        steps_per_period = auto_steps_per_period(system.omega, system.omega_max, order, samples_per_period,
                                                 body_pairs=body_pairs)
    if steps_per_period <= 0 or samples_per_period <= 0:
        raise SimulationError("steps and samples per period must be positive")
    if steps_per_period % samples_per_period:
        raise SimulationError(
            f"steps per period ({steps_per_period}) must be a multiple of the "
            f"samples per period ({samples_per_period})"
        )
    h = system.period / steps_per_period
    n_steps = int(round(cycles * steps_per_period))
    sample_every = steps_per_period // samples_per_period * decimate
    n_out = n_steps // sample_every + 2
    setting = {
        "steps_per_period": steps_per_period,
        "step_s": h,
        "composition": composition,
        "order": order,
        "stages": len(weights),
        "samples_per_period": samples_per_period,
        "decimate": decimate,
    }
    if chosen_by:
        setting["chosen_by"] = chosen_by
    if system.reduced is not None:
        rf = system.reduced
        out_t, out_y, out_yd = np.empty(n_out), np.empty(n_out), np.empty(n_out)
        status, _, n_s, n_force = run_reduced(
            rf.form,
            rf.jc,
            rf.js,
            rf.omega,
            rf.phase,
            rf.y0,
            rf.yd0,
            t0,
            h,
            n_steps,
            sample_every,
            weights,
            out_t,
            out_y,
            out_yd,
        )
        return RawRun(
            name,
            setting,
            int(status),
            float("nan"),
            int(n_force),
            out_t[:n_s].copy(),
            y=out_y[:n_s].copy(),
            yd=out_yd[:n_s].copy(),
        )
    check_memory(n_out, system.x0.shape[0])
    shape = scene_shape(system)
    compile_s = _warm_up(system, weights, shape)
    status, event_time, n_force, t, samples = _integrate_rigid(system, weights, shape, t0, h, n_steps,
                                                               sample_every, n_out)
    setting["kernel"] = shape
    return RawRun(name, setting, status, event_time, n_force, t, **samples, extra={"compile_s": compile_s})


def _integrate_rigid(
    system: CompiledSystem,
    weights: np.ndarray,
    shape: str,
    t0: float,
    h: float,
    n_steps: int,
    sample_every: int,
    n_out: int,
) -> tuple[int, float, int, np.ndarray, dict[str, np.ndarray]]:
    """Run the kernel of the scene's ``shape`` from the initial state into ``n_out`` sample rows.

    Returns ``(status, event_time, n_force, t, samples)``, ``samples`` holding the sampled
    ``x, v, R, L``, the damping ``budget`` and the magnetic ``impulse``.
    """
    nb = system.x0.shape[0]
    state = tuple(a.copy() for a in (system.x0, system.v0, system.R0, system.L0))
    out = (np.empty(n_out), np.empty((n_out, nb, 3)), np.empty((n_out, nb, 3)), np.empty((n_out, nb, 3, 3)),
           np.empty((n_out, nb, 3)), np.zeros(n_out), np.zeros((nb, 3)))
    args = system.kernel_args()
    if shape == "fixed_top":
        turn = stage_turns(weights, h, system.src, system.fld)
        result = run_fixed_top(state, t0, h, n_steps, sample_every, weights, args, out, turn)
    elif shape == "free_pair":
        result = run_free_pair(state, t0, h, n_steps, sample_every, weights, args, out)
    else:
        check_events = bool(system.bi[:, 0].any())
        result = run_rigid(state, t0, h, n_steps, sample_every, weights, args, out, check_events)
    status, _, n_s, event_time, n_force = result
    out_t, out_x, out_v, out_R, out_L, out_acc, impulse = out
    samples = {
        "x": _rows(out_x, n_s),
        "v": _rows(out_v, n_s),
        "R": _rows(out_R, n_s),
        "L": _rows(out_L, n_s),
        "impulse": impulse,
        "budget": _rows(out_acc, n_s),
    }
    return int(status), float(event_time), int(n_force), _rows(out_t, n_s), samples


def _rows(buffer: np.ndarray, n: int) -> np.ndarray:
    """The first ``n`` sample rows: the buffer itself when full (no second copy of a long run)."""
    return buffer if n == len(buffer) else buffer[:n].copy()


_WARM: set[str] = set()


def _warm_up(system: CompiledSystem, weights: np.ndarray, shape: str) -> float:
    """Load (or compile) the kernel with a zero-step call, so run time excludes it; returns seconds."""
    import time

    if shape in _WARM:
        return 0.0
    start = time.perf_counter()
    _integrate_rigid(system, weights, shape, 0.0, 1.0, 0, 1, 2)
    _WARM.add(shape)
    return time.perf_counter() - start
