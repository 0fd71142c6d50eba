"""Step kernels specialised to a compiled scene's shape (numba, cached).

:func:`labkit.sim.integrators.splitting.run_rigid` integrates any rigid scene: every stage loops
over bodies, checks the scene's flags and calls the general force routine. A scene whose shape
is known needs much less. :func:`scene_shape` names the shape; :data:`KERNELS` maps a shape to
its kernel; the general kernel serves every other scene. Every kernel takes the same packed
arguments (:class:`labkit.sim.integrators.splitting.KernelArgs`) and returns the same
``(status, steps_done, n_samples, event_time, n_force)``, with the status codes of
:class:`labkit.sim.integrators.Status`.

``fixed_top``: one body held in place (no translation), a symmetric top (two equal principal
moments, or all three), with a dipole, driven by a uniform field and/or rotators, no damping,
no gravity on a fixed body: the state is R and L, the stage is the same splitting as the general
kernel (half kick, exact free rotation, force, half kick) with the force and torque of each
source fused into the stage and no loop over bodies or flags. The same arithmetic in the same
order, so results agree with the general kernel to round-off.
"""

from __future__ import annotations

import math

from numba import njit

from labkit.sim.integrators.kernels import (
    B_I,
    B_M,
    B_OFF,
    F_DAMPING,
    F_FIELD,
    F_PAIRS,
    F_SOURCES,
    I_DIPOLE,
    I_FREE,
    I_TRANS,
    dipole_force_torque,
    source_state,
    uniform_field,
)
from labkit.sim.integrators.splitting import (
    ST_BLOWUP,
    ST_NONFINITE,
    ST_OK,
    rotate_axis_angle,
    rotate_body_columns,
    store_sample,
)


def scene_shape(system) -> str:
    """The shape of a compiled rigid scene that selects its step kernel ("general" otherwise)."""
    bf, bi, flags = system.bf, system.bi, system.flags
    if bf is None or bf.shape[0] != 1:
        return "general"
    one_fixed_top = (not bi[0, I_TRANS] and bi[0, I_FREE] == 0 and bi[0, I_DIPOLE]
                     and not flags[F_DAMPING] and not flags[F_PAIRS])
    return "fixed_top" if one_fixed_top else "general"


@njit(cache=True, _nrt=False)
def _top_torque(t, M, bf, src, fld, flags, x, ft):
    """Force and torque about the CM on the one body (into ``ft[0:6]``); fused, no loops over bodies."""
    mx = M[0, 0] * bf[0, B_M] + M[0, 1] * bf[0, B_M + 1] + M[0, 2] * bf[0, B_M + 2]
    my = M[1, 0] * bf[0, B_M] + M[1, 1] * bf[0, B_M + 1] + M[1, 2] * bf[0, B_M + 2]
    mz = M[2, 0] * bf[0, B_M] + M[2, 1] * bf[0, B_M + 1] + M[2, 2] * bf[0, B_M + 2]
    ox = M[0, 0] * bf[0, B_OFF] + M[0, 1] * bf[0, B_OFF + 1] + M[0, 2] * bf[0, B_OFF + 2]
    oy = M[1, 0] * bf[0, B_OFF] + M[1, 1] * bf[0, B_OFF + 1] + M[1, 2] * bf[0, B_OFF + 2]
    oz = M[2, 0] * bf[0, B_OFF] + M[2, 1] * bf[0, B_OFF + 1] + M[2, 2] * bf[0, B_OFF + 2]
    fx = fy = fz = tx = ty = tz = 0.0
    if flags[F_FIELD]:
        bx, by, bz = uniform_field(fld, t)
        tx += my * bz - mz * by
        ty += mz * bx - mx * bz
        tz += mx * by - my * bx
    if flags[F_SOURCES]:
        px, py, pz = x[0, 0] + ox, x[0, 1] + oy, x[0, 2] + oz
        for s in range(src.shape[0]):
            smx, smy, smz, spx, spy, spz = source_state(src, s, t)
            f = dipole_force_torque(smx, smy, smz, mx, my, mz, px - spx, py - spy, pz - spz)
            fx += f[0]
            fy += f[1]
            fz += f[2]
            tx += f[3] + oy * f[2] - oz * f[1]
            ty += f[4] + oz * f[0] - ox * f[2]
            tz += f[5] + ox * f[1] - oy * f[0]
    ft[0], ft[1], ft[2], ft[3], ft[4], ft[5] = fx, fy, fz, tx, ty, tz


@njit(cache=True, _nrt=False)
def _top_rotation(M, L, i_r, i_a, h):
    """Exact free rotation of a symmetric top (as :func:`..splitting.free_rotation`, kind 0)."""
    lx, ly, lz = L[0, 0], L[0, 1], L[0, 2]
    ln = math.sqrt(lx * lx + ly * ly + lz * lz)
    l3 = M[0, 2] * lx + M[1, 2] * ly + M[2, 2] * lz
    c = l3 * (1.0 / i_a - 1.0 / i_r)
    if c != 0.0:
        rotate_body_columns(M, 2, h * c)
    if ln > 0.0:
        rotate_axis_angle(M, lx / ln, ly / ln, lz / ln, h * ln / i_r)


@njit(cache=True)
def run_fixed_top(state, t0, h, n_steps, sample_every, weights, args, out, ft):
    """The ``fixed_top`` kernel; ``state = (x, v, R, L)`` updated in place, ``ft`` scratch (6,)."""
    x, v, R, L = state
    bf, bi, src, fld, flags, g, axis, r_escape, wz = args
    out_t, out_x, out_v, out_R, out_L, out_acc, impulse = out
    M = R[0]
    i_r, i_a = bf[0, B_I], bf[0, B_I + 2]
    t = t0
    _top_torque(t, M, bf, src, fld, flags, x, ft)
    n_force = 1
    n_s = store_sample(0, t, x, v, R, L, 0.0, out)
    status = ST_OK
    event_time = math.nan
    steps_done = 0
    for step in range(n_steps):
        for w in weights:
            hw = w * h
            half = 0.5 * hw
            for k in range(3):
                L[0, k] += half * ft[3 + k]
                impulse[0, k] += half * ft[k]
            _top_rotation(M, L, i_r, i_a, hw)
            t += hw
            _top_torque(t, M, bf, src, fld, flags, x, ft)
            n_force += 1
            for k in range(3):
                L[0, k] += half * ft[3 + k]
                impulse[0, k] += half * ft[k]
        t = t0 + (step + 1) * h
        steps_done = step + 1
        lx, ly, lz = L[0, 0], L[0, 1], L[0, 2]
        if not (math.isfinite(lx) and math.isfinite(ly) and math.isfinite(lz)):
            status, event_time = ST_NONFINITE, t
            break
        if math.sqrt(lx * lx + ly * ly + lz * lz) / bf[0, B_I] > 1e9:
            status, event_time = ST_BLOWUP, t
            break
        if (step + 1) % sample_every == 0:
            n_s = store_sample(n_s, t, x, v, R, L, 0.0, out)
    if status != ST_OK or steps_done % sample_every != 0:
        n_s = store_sample(n_s, t, x, v, R, L, 0.0, out)
    return status, steps_done, n_s, event_time, n_force
