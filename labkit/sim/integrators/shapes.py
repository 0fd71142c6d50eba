"""Step kernels specialised to a compiled scene's shape (numba, cached).

:func:`labkit.sim.integrators.splitting.run_rigid` integrates any rigid scene: every stage loops
over bodies, checks the scene's flags and calls the general force routine. A scene whose shape
is known needs much less. :func:`scene_shape` names the shape;
:func:`labkit.sim.integrators.splitting_run._integrate_rigid` runs its kernel, and the general
kernel serves every other scene. Every kernel takes the same packed arguments
(``CompiledSystem.kernel_args()``) and returns the same
``(status, steps_done, n_samples, event_time, n_force)``, with the status codes of
:class:`labkit.sim.integrators.Status`.

``fixed_top``: one body held in place (no translation), a symmetric top (two equal principal
moments, or all three), with a dipole, driven by a uniform field and/or rotators, no damping,
no gravity on a fixed body: the state is R and L, the stage is the same splitting as the general
kernel (half kick, exact free rotation, force, half kick) with the force and torque of each
source fused into the stage and no loop over bodies or flags. R, L, the force, the torque and the
impulse stay in local scalars between samples and the stage's helpers are inlined into the step
loop (``inline="always"``), with no arrays the compiler must assume may alias and no calls that
pass each array as a dozen scalars: a stage of conical_5_1 takes 60 ns instead of 84
(docs/reference/simulator.md, docs/decisions/0042-kernel-state-in-local-variables.md), with results
bit for bit the same. The same terms as the general kernel; the drive phases are turned by
products (:func:`stage_turns`) where the general kernel takes cos and sin of each stage's time,
so results agree with it to round-off growth.

``free_pair``: two free symmetric tops with dipoles and nothing else (no field, rotator, gravity or
damping; the bound state of Fig. 6.1): the pair's force and torque fused, no flag checks. Within
a step both bodies' state, forces and impulse are local tuples, the helpers inlined; x, v and L
go back to the arrays after each step for the health and event checks, R at samples.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from labkit.sim.integrators.kernels import (
    B_I,
    B_M,
    B_MASS,
    B_OFF,
    F_DAMPING,
    F_FIELD,
    F_GRAVITY,
    F_PAIRS,
    F_SOURCES,
    I_DIPOLE,
    I_FREE,
    I_TRANS,
    K_M,
    S_AXIS,
    S_MOM,
    S_OMEGA,
    S_RAMP,
    S_SHIFT,
    S_TILT,
    dipole_force_torque,
    source_angle,
)
from labkit.sim.integrators.splitting import (
    ST_BLOWUP,
    ST_NONFINITE,
    ST_OK,
    axis_angle_matrix,
    health,
    step_event,
    store_sample,
)


def scene_shape(system) -> str:
    """The shape of a compiled rigid scene that selects its step kernel ("general" otherwise)."""
    bf, bi, flags = system.bf, system.bi, system.flags
    if bf is None:
        return "general"
    if bf.shape[0] == 2:
        free_pair = (all(bi[b, I_TRANS] and bi[b, I_FREE] == 0 and bi[b, I_DIPOLE] for b in range(2))
                     and flags[F_PAIRS] and not (flags[F_FIELD] or flags[F_SOURCES] or flags[F_GRAVITY]
                                                 or flags[F_DAMPING]))
        return "free_pair" if free_pair else "general"
    if bf.shape[0] != 1:
        return "general"
    one_fixed_top = (not bi[0, I_TRANS] and bi[0, I_FREE] == 0 and bi[0, I_DIPOLE]
                     and not flags[F_DAMPING] and not flags[F_PAIRS])
    return "fixed_top" if one_fixed_top else "general"


@njit(cache=True, _nrt=False)
def _drive_phases(t, src, fld, ph):
    """cos and sin of every drive angle at ``t``: row 0 the field's, row 1 + s rotator s's."""
    th = fld[4] + fld[3] * t
    ph[0, 0], ph[0, 1] = math.cos(th), math.sin(th)
    for s in range(src.shape[0]):
        th = source_angle(src, s, t)
        ph[1 + s, 0], ph[1 + s, 1] = math.cos(th), math.sin(th)


@njit(cache=True, _nrt=False, inline="always")
def _advance_phases(base, turn, i, t, src, ph):
    """Drive phases at stage ``i`` of a step: the step's ``base`` phases turned by the stage's
    precomputed angle (``turn[d, i]``: cos, sin of rate x stage offset), two products instead
    of a cos and a sin; a ramped rotator is evaluated directly at ``t``."""
    for d in range(base.shape[0]):
        if d > 0 and src[d - 1, S_RAMP] != 0.0:
            th = source_angle(src, d - 1, t)
            ph[d, 0], ph[d, 1] = math.cos(th), math.sin(th)
            continue
        c0, s0, c1, s1 = base[d, 0], base[d, 1], turn[d, i, 0], turn[d, i, 1]
        ph[d, 0] = c0 * c1 - s0 * s1
        ph[d, 1] = s0 * c1 + c0 * s1


def stage_turns(weights, h, src, fld) -> np.ndarray:
    """(drives, stages, 2): cos and sin of each drive's rate times each stage's offset in the step."""
    offsets = np.cumsum(weights) * h
    rates = np.concatenate([[fld[3]], src[:, S_OMEGA]])
    angles = rates[:, None] * offsets[None, :]
    return np.stack([np.cos(angles), np.sin(angles)], axis=-1)


@njit(cache=True, _nrt=False)
def _source_tilts(src, tilts):
    """cos and sin of each source's tilt, once per run (constants of the scene, read by
    :func:`_top_force` at every stage)."""
    for s in range(src.shape[0]):
        tilts[s, 0], tilts[s, 1] = math.cos(src[s, S_TILT]), math.sin(src[s, S_TILT])


@njit(cache=True, _nrt=False, inline="always")
def _top_turn(m00, m01, m02, m10, m11, m12, m20, m21, m22, lx, ly, lz, i_r, k_a, h):
    """Exact free rotation of a symmetric top over ``h`` on the rotation held in scalars (the
    arithmetic of :func:`..splitting.free_rotation`, kind 0, in the same order); ``k_a`` is
    ``1/I_A - 1/I_R``. Returns the nine entries of the turned rotation, row by row."""
    ln = math.sqrt(lx * lx + ly * ly + lz * lz)
    l3 = m02 * lx + m12 * ly + m22 * lz
    c = l3 * k_a
    if c != 0.0:  # right-multiply by the rotation about body z by h c (rotate_body_columns)
        angle = h * c
        cz, sz = math.cos(angle), math.sin(angle)
        m00, m01 = cz * m00 + sz * m01, -sz * m00 + cz * m01
        m10, m11 = cz * m10 + sz * m11, -sz * m10 + cz * m11
        m20, m21 = cz * m20 + sz * m21, -sz * m20 + cz * m21
    if ln > 0.0:  # left-multiply by the rotation about L by h |L| / I_R (rotate_axis_angle)
        ax, ay, az = lx / ln, ly / ln, lz / ln
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = axis_angle_matrix(ax, ay, az, h * ln / i_r)
        m00, m10, m20 = (r00 * m00 + r01 * m10 + r02 * m20, r10 * m00 + r11 * m10 + r12 * m20,
                         r20 * m00 + r21 * m10 + r22 * m20)
        m01, m11, m21 = (r00 * m01 + r01 * m11 + r02 * m21, r10 * m01 + r11 * m11 + r12 * m21,
                         r20 * m01 + r21 * m11 + r22 * m21)
        m02, m12, m22 = (r00 * m02 + r01 * m12 + r02 * m22, r10 * m02 + r11 * m12 + r12 * m22,
                         r20 * m02 + r21 * m12 + r22 * m22)
    return m00, m01, m02, m10, m11, m12, m20, m21, m22
@njit(cache=True, _nrt=False, inline="always")
def _top_force(m00, m01, m02, m10, m11, m12, m20, m21, m22, bf, src, fld, flags, x, ph, tilts):
    """Force and torque about the CM on the one body with the rotation held in scalars, the
    drive phases ``ph`` (:func:`_drive_phases`) and each source's ``tilts``
    (:func:`_source_tilts`); fused, no loops over bodies. Returns ``(Fx, Fy, Fz, tx, ty, tz)``."""
    bm0, bm1, bm2 = bf[0, B_M], bf[0, B_M + 1], bf[0, B_M + 2]
    mx = m00 * bm0 + m01 * bm1 + m02 * bm2
    my = m10 * bm0 + m11 * bm1 + m12 * bm2
    mz = m20 * bm0 + m21 * bm1 + m22 * bm2
    fx = fy = fz = tx = ty = tz = 0.0
    if flags[F_FIELD]:  # Eq. 5.21 (rotating or static) or Eq. 5.481 (oscillating), as uniform_field
        c, sn = ph[0, 0], ph[0, 1]
        bx, by, bz = (-fld[1] * sn, fld[1] * c, fld[2]) if fld[0] == 1.0 else (0.0, fld[1] * c, fld[2])
        tx += my * bz - mz * by
        ty += mz * bx - mx * bz
        tz += mx * by - my * bx
    if flags[F_SOURCES]:
        bo0, bo1, bo2 = bf[0, B_OFF], bf[0, B_OFF + 1], bf[0, B_OFF + 2]
        ox = m00 * bo0 + m01 * bo1 + m02 * bo2
        oy = m10 * bo0 + m11 * bo1 + m12 * bo2
        oz = m20 * bo0 + m21 * bo1 + m22 * bo2
        px, py, pz = x[0, 0] + ox, x[0, 1] + oy, x[0, 2] + oz
        for s in range(src.shape[0]):
            c, sn = ph[1 + s, 0], ph[1 + s, 1]  # Eq. 5.25, as source_state
            mom = src[s, S_MOM]
            m0y, m0z = -mom * tilts[s, 0], mom * tilts[s, 1]
            sx, sy, sz = src[s, S_SHIFT], src[s, S_SHIFT + 1], src[s, S_SHIFT + 2]
            spx = src[s, S_AXIS] + c * sx - sn * sy
            spy = src[s, S_AXIS + 1] + sn * sx + c * sy
            spz = src[s, S_AXIS + 2] + sz
            f = dipole_force_torque(-sn * m0y, c * m0y, m0z, mx, my, mz, px - spx, py - spy, pz - spz)
            fx += f[0]
            fy += f[1]
            fz += f[2]
            tx += f[3] + oy * f[2] - oz * f[1]
            ty += f[4] + oz * f[0] - ox * f[2]
            tz += f[5] + ox * f[1] - oy * f[0]
    return fx, fy, fz, tx, ty, tz


@njit(cache=True)
def run_fixed_top(state, t0, h, n_steps, sample_every, weights, args, out, turn):
    """The ``fixed_top`` kernel; ``state = (x, v, R, L)`` updated in place; ``turn`` from
    :func:`stage_turns` (the drive phases of each stage relative to its step's start). The
    rotation, angular momentum, force, torque and impulse stay in local scalars between samples."""
    x, v, R, L = state
    bf, bi, src, fld, flags, g, axis, r_escape, wz = args
    impulse = out[6]
    i_r, i_a = bf[0, B_I], bf[0, B_I + 2]
    k_a = 1.0 / i_a - 1.0 / i_r
    base = np.empty((1 + src.shape[0], 2))
    ph = np.empty((1 + src.shape[0], 2))
    tilts = np.empty((src.shape[0], 2))
    _source_tilts(src, tilts)
    m00, m01, m02 = R[0, 0, 0], R[0, 0, 1], R[0, 0, 2]
    m10, m11, m12 = R[0, 1, 0], R[0, 1, 1], R[0, 1, 2]
    m20, m21, m22 = R[0, 2, 0], R[0, 2, 1], R[0, 2, 2]
    lx, ly, lz = L[0, 0], L[0, 1], L[0, 2]
    p0, p1, p2 = impulse[0, 0], impulse[0, 1], impulse[0, 2]
    t = t0
    _drive_phases(t, src, fld, ph)
    fx, fy, fz, tx, ty, tz = _top_force(m00, m01, m02, m10, m11, m12, m20, m21, m22, bf, src, fld, flags, x,
                                        ph, tilts)
    n_force = 1
    n_s = store_sample(0, t, x, v, R, L, 0.0, out)
    status = ST_OK
    event_time = math.nan
    steps_done = 0
    for step in range(n_steps):
        _drive_phases(t, src, fld, base)
        for i in range(weights.shape[0]):
            hw = weights[i] * h
            half = 0.5 * hw
            lx, ly, lz = lx + half * tx, ly + half * ty, lz + half * tz
            p0, p1, p2 = p0 + half * fx, p1 + half * fy, p2 + half * fz
            m00, m01, m02, m10, m11, m12, m20, m21, m22 = _top_turn(m00, m01, m02, m10, m11, m12, m20, m21,
                                                                    m22, lx, ly, lz, i_r, k_a, hw)
            t += hw
            _advance_phases(base, turn, i, t, src, ph)
            fx, fy, fz, tx, ty, tz = _top_force(m00, m01, m02, m10, m11, m12, m20, m21, m22, bf, src, fld,
                                                flags, x, ph, tilts)
            n_force += 1
            lx, ly, lz = lx + half * tx, ly + half * ty, lz + half * tz
            p0, p1, p2 = p0 + half * fx, p1 + half * fy, p2 + half * fz
        t = t0 + (step + 1) * h
        steps_done = step + 1
        if not (math.isfinite(lx) and math.isfinite(ly) and math.isfinite(lz)):
            status, event_time = ST_NONFINITE, t
            break
        if math.sqrt(lx * lx + ly * ly + lz * lz) / i_r > 1e9:
            status, event_time = ST_BLOWUP, t
            break
        if (step + 1) % sample_every == 0:
            _put_top(R, L, m00, m01, m02, m10, m11, m12, m20, m21, m22, lx, ly, lz)
            n_s = store_sample(n_s, t, x, v, R, L, 0.0, out)
    _put_top(R, L, m00, m01, m02, m10, m11, m12, m20, m21, m22, lx, ly, lz)
    impulse[0, 0], impulse[0, 1], impulse[0, 2] = p0, p1, p2
    if status != ST_OK or steps_done % sample_every != 0:
        n_s = store_sample(n_s, t, x, v, R, L, 0.0, out)
    return status, steps_done, n_s, event_time, n_force


@njit(cache=True, _nrt=False)
def _put_top(R, L, m00, m01, m02, m10, m11, m12, m20, m21, m22, lx, ly, lz):
    """Write the rotation and angular momentum held in scalars back into the state arrays."""
    R[0, 0, 0], R[0, 0, 1], R[0, 0, 2] = m00, m01, m02
    R[0, 1, 0], R[0, 1, 1], R[0, 1, 2] = m10, m11, m12
    R[0, 2, 0], R[0, 2, 1], R[0, 2, 2] = m20, m21, m22
    L[0, 0], L[0, 1], L[0, 2] = lx, ly, lz


@njit(cache=True, _nrt=False, inline="always")
def _pair_force_torque(ax, ay, az, bx, by, bz, rx, ry, rz):
    """Eq. 4.2-4.3 for both dipoles of a pair at once (``r`` from a to b): the force on a is minus
    the force on b; the torques share ``a x b`` and the projections on ``u = r / |r|``. Returns
    ``(F_b, tau_b), (F_a, tau_a)`` as two 6-tuples (as :func:`..kernels.dipole_force_torque`)."""
    d2 = rx * rx + ry * ry + rz * rz
    d = math.sqrt(d2)
    ux, uy, uz = rx / d, ry / d, rz / d
    ab = ax * bx + ay * by + az * bz
    ra = ux * ax + uy * ay + uz * az
    rb = ux * bx + uy * by + uz * bz
    cf = 3.0 * K_M / (d2 * d2)
    fx = cf * (ux * ab + ax * rb + bx * ra - 5.0 * ux * ra * rb)
    fy = cf * (uy * ab + ay * rb + by * ra - 5.0 * uy * ra * rb)
    fz = cf * (uz * ab + az * rb + bz * ra - 5.0 * uz * ra * rb)
    ct = K_M / (d2 * d)
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx  # a x b
    tbx = ct * (3.0 * ra * (by * uz - bz * uy) + cx)
    tby = ct * (3.0 * ra * (bz * ux - bx * uz) + cy)
    tbz = ct * (3.0 * ra * (bx * uy - by * ux) + cz)
    tax = ct * (3.0 * rb * (ay * uz - az * uy) - cx)
    tay = ct * (3.0 * rb * (az * ux - ax * uz) - cy)
    taz = ct * (3.0 * rb * (ax * uy - ay * ux) - cz)
    return (fx, fy, fz, tbx, tby, tbz), (-fx, -fy, -fz, tax, tay, taz)


@njit(cache=True, _nrt=False, inline="always")
def _lab_dipole(r, xb, mb, ob):
    """Lab moment and dipole position of a body with rotation ``r`` (9-tuple, row by row) at CM
    ``xb``; ``mb``, ``ob`` its body-frame moment and offset. Sums in the order of
    :func:`..kernels.body_dipoles` (from 0.0, column by column)."""
    m = (0.0 + r[0] * mb[0] + r[1] * mb[1] + r[2] * mb[2],
         0.0 + r[3] * mb[0] + r[4] * mb[1] + r[5] * mb[2],
         0.0 + r[6] * mb[0] + r[7] * mb[1] + r[8] * mb[2])
    p = (xb[0] + (0.0 + r[0] * ob[0] + r[1] * ob[1] + r[2] * ob[2]),
         xb[1] + (0.0 + r[3] * ob[0] + r[4] * ob[1] + r[5] * ob[2]),
         xb[2] + (0.0 + r[6] * ob[0] + r[7] * ob[1] + r[8] * ob[2]))
    return m, p


@njit(cache=True, _nrt=False, inline="always")
def _about_cm(f, p, xb):
    """Force and torque about the CM ``xb`` from a dipole's force and torque ``f`` at ``p``."""
    ox, oy, oz = p[0] - xb[0], p[1] - xb[1], p[2] - xb[2]
    return (f[0], f[1], f[2]), (f[3] + oy * f[2] - oz * f[1], f[4] + oz * f[0] - ox * f[2],
                                f[5] + ox * f[1] - oy * f[0])


@njit(cache=True, _nrt=False, inline="always")
def _pair_forces(r0, r1, x0, x1, body):
    """Dipole-dipole force and torque (about each CM) on both bodies: ``(F0, T0, F1, T1)``;
    ``body`` holds each body's moment and offset. The arithmetic of
    :func:`..kernels.compute_forces`, fused."""
    m0, p0 = _lab_dipole(r0, x0, body[0], body[1])
    m1, p1 = _lab_dipole(r1, x1, body[2], body[3])
    fb, fa = _pair_force_torque(m0[0], m0[1], m0[2], m1[0], m1[1], m1[2], p1[0] - p0[0], p1[1] - p0[1],
                                p1[2] - p0[2])
    f1, t1 = _about_cm(fb, p1, x1)
    f0, t0 = _about_cm(fa, p0, x0)
    return f0, t0, f1, t1


@njit(cache=True, _nrt=False, inline="always")
def _kick(vb, lb, pb, fb, tb, inv_m, h):
    """Half kick of one body: velocity, angular momentum and impulse, as 3-tuples."""
    return ((vb[0] + h * fb[0] * inv_m, vb[1] + h * fb[1] * inv_m, vb[2] + h * fb[2] * inv_m),
            (lb[0] + h * tb[0], lb[1] + h * tb[1], lb[2] + h * tb[2]),
            (pb[0] + h * fb[0], pb[1] + h * fb[1], pb[2] + h * fb[2]))


@njit(cache=True, _nrt=False, inline="always")
def _drift(xb, vb, r, lb, i_r, k_a, h):
    """Free flight of the CM and exact free rotation (:func:`_top_turn`) of one body over ``h``."""
    return ((xb[0] + h * vb[0], xb[1] + h * vb[1], xb[2] + h * vb[2]),
            _top_turn(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], lb[0], lb[1], lb[2], i_r, k_a, h))


@njit(cache=True, _nrt=False)
def _put_body(b, x, v, L, xb, vb, lb):
    for k in range(3):
        x[b, k], v[b, k], L[b, k] = xb[k], vb[k], lb[k]


@njit(cache=True, _nrt=False, inline="always")
def _rotation(R, b):
    """Body ``b``'s rotation as a 9-tuple, row by row."""
    return (R[b, 0, 0], R[b, 0, 1], R[b, 0, 2], R[b, 1, 0], R[b, 1, 1], R[b, 1, 2], R[b, 2, 0], R[b, 2, 1],
            R[b, 2, 2])


@njit(cache=True, _nrt=False)
def _put_rotation(b, R, r):
    for i in range(3):
        for j in range(3):
            R[b, i, j] = r[3 * i + j]


@njit(cache=True)
def run_free_pair(state, t0, h, n_steps, sample_every, weights, args, out):
    """The ``free_pair`` kernel; ``state = (x, v, R, L)`` in place. Within a step the state, forces
    and impulse are local tuples; x, v and L go back to the arrays after each step (the health and
    event checks read them), R at samples."""
    x, v, R, L = state
    bf, bi, src, fld, flags, g, axis, r_escape, wz = args
    impulse = out[6]
    xp, vp = np.empty((2, 3)), np.empty((2, 3))
    inv_m0, inv_m1 = 1.0 / bf[0, B_MASS], 1.0 / bf[1, B_MASS]
    i_r0, i_r1 = bf[0, B_I], bf[1, B_I]
    k_a0, k_a1 = 1.0 / bf[0, B_I + 2] - 1.0 / i_r0, 1.0 / bf[1, B_I + 2] - 1.0 / i_r1
    body = ((bf[0, B_M], bf[0, B_M + 1], bf[0, B_M + 2]), (bf[0, B_OFF], bf[0, B_OFF + 1], bf[0, B_OFF + 2]),
            (bf[1, B_M], bf[1, B_M + 1], bf[1, B_M + 2]), (bf[1, B_OFF], bf[1, B_OFF + 1], bf[1, B_OFF + 2]))
    x0, x1 = (x[0, 0], x[0, 1], x[0, 2]), (x[1, 0], x[1, 1], x[1, 2])
    v0, v1 = (v[0, 0], v[0, 1], v[0, 2]), (v[1, 0], v[1, 1], v[1, 2])
    l0, l1 = (L[0, 0], L[0, 1], L[0, 2]), (L[1, 0], L[1, 1], L[1, 2])
    q0, q1 = (impulse[0, 0], impulse[0, 1], impulse[0, 2]), (impulse[1, 0], impulse[1, 1], impulse[1, 2])
    r0, r1 = _rotation(R, 0), _rotation(R, 1)
    t = t0
    f0, tq0, f1, tq1 = _pair_forces(r0, r1, x0, x1, body)
    n_force = 1
    n_s = store_sample(0, t, x, v, R, L, 0.0, out)
    status = ST_OK
    event_time = math.nan
    steps_done = 0
    for step in range(n_steps):
        xp[:] = x
        vp[:] = v
        for w in weights:
            hw = w * h
            v0, l0, q0 = _kick(v0, l0, q0, f0, tq0, inv_m0, 0.5 * hw)
            v1, l1, q1 = _kick(v1, l1, q1, f1, tq1, inv_m1, 0.5 * hw)
            x0, r0 = _drift(x0, v0, r0, l0, i_r0, k_a0, hw)
            x1, r1 = _drift(x1, v1, r1, l1, i_r1, k_a1, hw)
            t += hw
            f0, tq0, f1, tq1 = _pair_forces(r0, r1, x0, x1, body)
            n_force += 1
            v0, l0, q0 = _kick(v0, l0, q0, f0, tq0, inv_m0, 0.5 * hw)
            v1, l1, q1 = _kick(v1, l1, q1, f1, tq1, inv_m1, 0.5 * hw)
        t = t0 + (step + 1) * h
        steps_done = step + 1
        _put_body(0, x, v, L, x0, v0, l0)
        _put_body(1, x, v, L, x1, v1, l1)
        status = health(x, v, L, bf)
        if status == ST_OK:
            status, event_time = step_event(x, v, xp, vp, bf, bi, src, r_escape, t, h)
        else:
            event_time = t
        if status != ST_OK:
            break
        if (step + 1) % sample_every == 0:
            _put_rotation(0, R, r0)
            _put_rotation(1, R, r1)
            n_s = store_sample(n_s, t, x, v, R, L, 0.0, out)
    _put_rotation(0, R, r0)
    _put_rotation(1, R, r1)
    for k in range(3):
        impulse[0, k], impulse[1, k] = q0[k], q1[k]
    if status != ST_OK or steps_done % sample_every != 0:
        n_s = store_sample(n_s, t, x, v, R, L, 0.0, out)
    return status, steps_done, n_s, event_time, n_force
