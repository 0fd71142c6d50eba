"""scipy ``solve_ivp`` references (DOP853, Radau, LSODA) with per-component tolerances.

State per body: position, velocity, rotation matrix (9), lab angular momentum;
``dR/dt = [Omega]x R`` with ``Omega = R I^-1 R^T L``. Appended: the time integral of each
body's magnetic force (3 per body, for the cycle-averaged force) and the damping's share of
``E - w J_z`` (1, for the energy or Jacobi budget). Absolute tolerances are ``rtol`` times
a scale per component (length, length * omega, 1, I * omega), so tiny bodies at high speed are
controlled as well as big slow ones (docs/explanation/numerics-notes.md#scaling). Contact and escape are
terminal events.
These are validation paths: their invariants drift (no geometric structure), which the result
reports.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from labkit.sim.compile import CompiledSystem
from labkit.sim.integrators.raw_run import RawRun, check_memory
from labkit.sim.integrators.rigid_rhs import STRIDE
from labkit.sim.integrators.splitting import reduced_acceleration


def _unpack(y: np.ndarray, nb: int):
    s = y[: nb * STRIDE].reshape(nb, STRIDE)
    return s[:, 0:3], s[:, 3:6], s[:, 6:15].reshape(nb, 3, 3), s[:, 15:18]


def _rigid_rhs(system: CompiledSystem, counter: list[int]):
    """``f(t, y)`` for solve_ivp: one call of the compiled right-hand side (the same one CyRK's
    DOP853 runs, :func:`labkit.sim.integrators.rigid_rhs.rigid_derivative`), so a scipy
    cross-check costs seconds; ``counter[0]`` counts calls."""
    from labkit.sim.integrators.rigid_rhs import pack_args, rigid_derivative

    args = pack_args(system)
    n = system.bf.shape[0] * (STRIDE + 3) + 1

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        counter[0] += 1
        dy = np.empty(n)
        rigid_derivative(t, y, dy, args)
        return dy

    return rhs


def sample_times(t0: float, t_end: float, n: int, dt: float, decimate: int = 1) -> np.ndarray:
    """Every ``decimate``-th of the ``n + 1`` sample times ``t0 + k dt``, and the last one (<= t_end)."""
    k = np.arange(0, n + 1, decimate)
    if k[-1] != n:
        k = np.append(k, n)
    t_eval = t0 + k * dt
    t_eval[-1] = min(t_eval[-1], t_end)
    return t_eval


def tolerance_scale(system: CompiledSystem) -> np.ndarray:
    """Scale per state component (length, length * omega, 1, I * omega; inf for the extras, which
    are outputs, not steered): absolute tolerances are ``rtol`` times this (docs/reference/bench-sim.md)."""
    nb = system.bf.shape[0]
    i_max = system.bf[:, 1:4].max(axis=1, keepdims=True)
    length = system.length_scale
    scale = np.concatenate(
        [
            np.full((nb, 3), length),
            np.full((nb, 3), length * system.omega_max),
            np.ones((nb, 9)),
            np.repeat(i_max * system.omega_max, 3, axis=1),
        ],
        axis=1,
    ).ravel()
    return np.concatenate([scale, np.full(3 * nb + 1, np.inf)])


def _events(system: CompiledSystem):
    bf, bi, src = system.bf, system.bi, system.src
    nb = bf.shape[0]
    movers = [b for b in range(nb) if bi[b, 0]]
    points = [(b, None) for b in range(nb)] + [(None, s) for s in range(src.shape[0])]

    def pairs(y):
        x = y[: nb * STRIDE].reshape(nb, STRIDE)[:, 0:3]
        for a in movers:
            for b, s in points:
                if b == a:
                    continue
                if b is not None:
                    yield a, np.linalg.norm(x[a] - x[b]), bf[a, 12] + bf[b, 12]
                else:
                    yield a, np.linalg.norm(x[a] - src[s, 8:11]), bf[a, 12] + src[s, 11]

    def contact(t, y):
        return min((d - r for _, d, r in pairs(y)), default=1.0)

    def escape(t, y):
        nearest = {}
        for a, d, _ in pairs(y):
            nearest[a] = min(nearest.get(a, math.inf), d)
        return system.r_escape - max(nearest.values(), default=0.0)

    contact.terminal, contact.direction = True, -1
    escape.terminal, escape.direction = True, -1
    return [contact, escape] if movers else []


def run(
    system: CompiledSystem,
    cycles: float,
    method: str,
    name: str,
    rtol: float = 1e-10,
    samples_per_period: int = 8,
    t0: float = 0.0,
    decimate: int = 1,
    **_: object,
) -> RawRun:
    """Integrate with ``solve_ivp(method)``; samples at exact multiples of ``T / samples_per_period``."""
    t_end = t0 + cycles * system.period
    n = int(round(cycles * samples_per_period))
    t_eval = sample_times(t0, t_end, n, system.period / samples_per_period, decimate)
    counter = [0]
    setting = {"method": method, "rtol": rtol, "samples_per_period": samples_per_period}
    if system.reduced is not None:
        rf = system.reduced

        def rhs(t, y):
            counter[0] += 1
            return [y[1], reduced_acceleration(rf.form, y[0], t, rf.jc, rf.js, rf.omega, rf.phase)]

        scale = np.array([1.0, max(system.omega_max, 1e-300)])
        sol = solve_ivp(
            rhs, (t0, t_end), [rf.y0, rf.yd0], method=method, t_eval=t_eval, rtol=rtol, atol=rtol * scale
        )
        status = 0 if sol.success else 5
        return RawRun(
            name, setting, status, math.nan, counter[0], sol.t, y=sol.y[0], yd=sol.y[1], message=sol.message
        )
    nb = system.bf.shape[0]
    check_memory(n + 2, nb)
    state0 = np.concatenate([system.x0, system.v0, system.R0.reshape(nb, 9), system.L0], axis=1).ravel()
    y0 = np.concatenate([state0, np.zeros(3 * nb + 1)])
    scale = tolerance_scale(system)
    events = _events(system) if system.r_escape or np.any(system.bi[:, 0]) else []
    if not system.r_escape and events:
        events = events[:1]
    sol = solve_ivp(
        _rigid_rhs(system, counter),
        (t0, t_end),
        y0,
        method=method,
        t_eval=t_eval,
        rtol=rtol,
        atol=rtol * scale,
        events=events or None,
    )
    full = sol.y.T
    status, event_time = (0 if sol.success else 5), math.nan
    if sol.status == 1 and sol.t_events is not None:
        for code, times, states in zip((3, 4), sol.t_events, sol.y_events, strict=False):
            if len(times):
                status, event_time = code, float(times[0])
                full = np.concatenate([full, states[:1]])
                sol_t = np.concatenate([sol.t, times[:1]])
                break
        else:
            sol_t = sol.t
    else:
        sol_t = sol.t
    ys = full[:, : nb * STRIDE].reshape(-1, nb, STRIDE)
    impulse = full[-1, nb * STRIDE : nb * STRIDE + 3 * nb].reshape(nb, 3)
    if not np.all(np.isfinite(ys)):
        status = 1
    x, v, R, L = ys[..., 0:3], ys[..., 3:6], ys[..., 6:15].reshape(-1, nb, 3, 3), ys[..., 15:18]
    return RawRun(
        name,
        setting,
        status,
        event_time,
        counter[0],
        np.asarray(sol_t),
        x=x.copy(),
        v=v.copy(),
        R=R.copy(),
        L=L.copy(),
        impulse=impulse.copy(),
        budget=full[:, -1].copy(),
        message=sol.message,
    )
