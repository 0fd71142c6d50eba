"""Fixed-step structure-preserving splitting integrators (numba, cached).

The base method is a symmetric Strang splitting (Dullweber-Leimkuhler-McLachlan 1997):
``damping(h/2) kick(h/2) drift(h) kick(h/2) damping(h/2)``, where

* kick: forces and torques of the scene at the current time change momenta;
* drift: free flight of the CM and *exact* free rotation: for a symmetric top (two equal
  principal moments, or all three) ``R(h) = exp(h [L]x / I_R) R exp(h c [e3]x)``,
  ``c = L3 (1/I_A - 1/I_R)``; for three unequal moments the DLM sequence of planar rotations
  X(h/2) Y(h/2) Z(h) Y(h/2) X(h/2);
* damping: the exact flow of linear damping (``v *= exp(-c h/m)``, body-frame
  ``pi_i *= exp(-c h / I_i)``).

Symmetric compositions raise the order: Yoshida's triple jump and Suzuki's 5-stage (order 4),
Yoshida's 7-stage and Kahan-Li's 9-stage (order 6), Yoshida's 15-stage and Kahan-Li's 17-stage
(order 8; Kahan and Li 1997, the coefficients tabulated in Hairer, Lubich and Wanner, Geometric
Numerical Integration, V.3.2). With ``h = T/N`` the Jacobi-type invariant of a uniformly driven
scene has no secular drift (docs/explanation/numerics-notes.md#the-jacobi-constant). Force evaluations are
shared between adjacent
kicks (first-same-as-last), so a step of an s-stage method costs s force evaluations.

Status codes returned by the kernels: the members of :class:`labkit.sim.integrators.Status`
(``ST_*`` here, plain ints for numba): ok, non-finite, blow-up, contact, escape.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from labkit.sim.integrators.kernels import (
    B_CLIN,
    B_CROT,
    B_I,
    B_MASS,
    B_RAD,
    F_DAMPING,
    F_GRAVITY,
    I_FREE,
    I_TRANS,
    S_AXIS,
    S_RAD,
    compute_forces,
)
from labkit.sim.integrators.status import Status

ST_OK, ST_NONFINITE, ST_BLOWUP = int(Status.OK), int(Status.NONFINITE), int(Status.BLOWUP)
ST_CONTACT, ST_ESCAPE = int(Status.CONTACT), int(Status.ESCAPE)


def _yoshida_triple(order_weights: list[float], order: int) -> list[float]:
    x1 = 1.0 / (2.0 - 2.0 ** (1.0 / (order + 1)))
    x0 = -(2.0 ** (1.0 / (order + 1))) * x1
    return [w * x1 for w in order_weights] + [w * x0 for w in order_weights] + [w * x1 for w in order_weights]


_P = 1.0 / (4.0 - 4.0 ** (1.0 / 3.0))
_Y6 = [0.784513610477560, 0.235573213359357, -1.17767998417887]  # Yoshida (1990) solution A: w3, w2, w1
_Y6_0 = 1.0 - 2.0 * sum(_Y6)

#: Yoshida (1990) 8th order, solution D: w7 ... w1 (w0 = 1 - 2 sum)
_Y8 = [0.914844246229740, 0.253693336566229, -1.44485223686048, -0.158240635368243, 1.93813913762276,
       -1.96061023297549, 0.102799849391985]
_Y8_0 = 1.0 - 2.0 * sum(_Y8)
#: Kahan and Li (1997) s9odr6a: 9 stages, order 6 (gamma_1 ... gamma_5, symmetric)
_KL6 = [0.39216144400731413928, 0.33259913678935943860, -0.70624617255763935981, 0.08221359629355080023,
        0.79854399093482996340]
#: Kahan and Li (1997) s17odr8a: 17 stages, order 8 (gamma_1 ... gamma_9, symmetric)
_KL8 = [0.13020248308889008088, 0.56116298177510838456, -0.38947496264484728641, 0.15884190655515560090,
        -0.39590389413323757734, 0.18453964097831570709, 0.25837438768632204729, 0.29501172360931029887,
        -0.60550853383003451170]


def _symmetric(half: list[float]) -> np.ndarray:
    """Weights g_1 ... g_m, g_{m-1} ... g_1 from their first half (the middle one last)."""
    return np.array(half + half[-2::-1])


#: name -> (stage weights of the symmetric base method, order)
COMPOSITIONS: dict[str, tuple[np.ndarray, int]] = {
    "strang": (np.array([1.0]), 2),
    "yoshida4": (np.array(_yoshida_triple([1.0], 2)), 4),
    "suzuki4": (np.array([_P, _P, 1.0 - 4.0 * _P, _P, _P]), 4),
    "yoshida6": (np.array([_Y6[0], _Y6[1], _Y6[2], _Y6_0, _Y6[2], _Y6[1], _Y6[0]]), 6),
    "kahanli6": (_symmetric(_KL6), 6),
    "yoshida8": (_symmetric(_Y8 + [_Y8_0]), 8),
    "kahanli8": (_symmetric(_KL8), 8),
}


@njit(cache=True, _nrt=False, inline="always")
def axis_angle_matrix(ax, ay, az, angle):
    """The rotation by ``angle`` about unit (ax, ay, az) (Rodrigues), its nine entries row by row."""
    c = math.cos(angle)
    s = math.sin(angle)
    t = 1.0 - c
    return (c + ax * ax * t, ax * ay * t - az * s, ax * az * t + ay * s,
            ay * ax * t + az * s, c + ay * ay * t, ay * az * t - ax * s,
            az * ax * t - ay * s, az * ay * t + ax * s, c + az * az * t)


@njit(cache=True, _nrt=False)
def rotate_axis_angle(M, ax, ay, az, angle):
    """Left-multiply the 3x3 matrix ``M`` in place by the rotation about unit (ax, ay, az)."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = axis_angle_matrix(ax, ay, az, angle)
    for j in range(3):
        a0, a1, a2 = M[0, j], M[1, j], M[2, j]
        M[0, j] = r00 * a0 + r01 * a1 + r02 * a2
        M[1, j] = r10 * a0 + r11 * a1 + r12 * a2
        M[2, j] = r20 * a0 + r21 * a1 + r22 * a2


@njit(cache=True, _nrt=False)
def rotate_body_columns(M, axis, angle):
    """Right-multiply the 3x3 matrix ``M`` in place by the rotation about body axis ``axis``.

    Returns ``(cos, sin)`` of ``angle`` for turning body-frame vectors along with it.
    """
    c = math.cos(angle)
    s = math.sin(angle)
    i = (axis + 1) % 3
    j = (axis + 2) % 3
    for r in range(3):
        a, b = M[r, i], M[r, j]
        M[r, i] = c * a + s * b
        M[r, j] = -s * a + c * b
    return c, s


@njit(cache=True, _nrt=False)
def _rotate_body_axis(M, pi, axis, angle):
    """:func:`rotate_body_columns` on ``M`` (Q), and the body-frame momentum pi <- Q^T pi."""
    c, s = rotate_body_columns(M, axis, angle)
    i = (axis + 1) % 3
    j = (axis + 2) % 3
    a, b = pi[i], pi[j]
    pi[i] = c * a + s * b
    pi[j] = -s * a + c * b


@njit(cache=True, _nrt=False)
def _body_momentum(R, L, b, pi):
    """pi <- R[b]^T L[b]: body ``b``'s angular momentum in its principal frame."""
    for k in range(3):
        pi[k] = R[b, 0, k] * L[b, 0] + R[b, 1, k] * L[b, 1] + R[b, 2, k] * L[b, 2]


@njit(cache=True, _nrt=False)
def free_rotation(R, L, bf, bi, b, h, pi):
    """Exact (symmetric top) or DLM (three unequal moments) free rotation of body ``b``."""
    M = R[b]
    if bi[b, I_FREE] == 0:
        i_r = bf[b, B_I]
        i_a = bf[b, B_I + 2]
        lx, ly, lz = L[b, 0], L[b, 1], L[b, 2]
        ln = math.sqrt(lx * lx + ly * ly + lz * lz)
        l3 = M[0, 2] * lx + M[1, 2] * ly + M[2, 2] * lz
        c = l3 * (1.0 / i_a - 1.0 / i_r)
        if c != 0.0:
            rotate_body_columns(M, 2, h * c)  # about body z by angle h c
        if ln > 0.0:
            rotate_axis_angle(M, lx / ln, ly / ln, lz / ln, h * ln / i_r)
    else:
        _body_momentum(R, L, b, pi)
        _rotate_body_axis(M, pi, 0, 0.5 * h * pi[0] / bf[b, B_I])
        _rotate_body_axis(M, pi, 1, 0.5 * h * pi[1] / bf[b, B_I + 1])
        _rotate_body_axis(M, pi, 2, h * pi[2] / bf[b, B_I + 2])
        _rotate_body_axis(M, pi, 1, 0.5 * h * pi[1] / bf[b, B_I + 1])
        _rotate_body_axis(M, pi, 0, 0.5 * h * pi[0] / bf[b, B_I])


@njit(cache=True, _nrt=False)
def _kinetic_jz(x, v, R, L, bf, bi, b, axis, pi):
    """(kinetic energy, J_z about the vertical line through ``axis``) of body ``b``."""
    e = 0.0
    jz = L[b, 2]
    if bi[b, I_TRANS]:
        m = bf[b, B_MASS]
        e += 0.5 * m * (v[b, 0] ** 2 + v[b, 1] ** 2 + v[b, 2] ** 2)
        jz += m * ((x[b, 0] - axis[0]) * v[b, 1] - (x[b, 1] - axis[1]) * v[b, 0])
    _body_momentum(R, L, b, pi)
    for k in range(3):
        e += 0.5 * pi[k] * pi[k] / bf[b, B_I + k]
    return e, jz


@njit(cache=True, _nrt=False)
def damping_flow(x, v, R, L, bf, bi, h, pi, wz, axis, acc):
    """Exact flow of linear translational and rotational damping over ``h``.

    ``acc[0]`` accumulates the change of ``E_kin - wz J_z`` it causes: the damping's share of
    the energy (``wz = 0``) or Jacobi budget, so that ``K - acc`` stays constant.
    """
    for b in range(v.shape[0]):
        lin = bi[b, I_TRANS] and bf[b, B_CLIN] > 0.0
        rot = bf[b, B_CROT] > 0.0
        if not (lin or rot):
            continue
        e0, j0 = _kinetic_jz(x, v, R, L, bf, bi, b, axis, pi)
        if lin:
            f = math.exp(-bf[b, B_CLIN] * h / bf[b, B_MASS])
            for k in range(3):
                v[b, k] *= f
        if rot:
            _body_momentum(R, L, b, pi)
            for k in range(3):
                pi[k] *= math.exp(-bf[b, B_CROT] * h / bf[b, B_I + k])
            for k in range(3):
                L[b, k] = R[b, k, 0] * pi[0] + R[b, k, 1] * pi[1] + R[b, k, 2] * pi[2]
        e1, j1 = _kinetic_jz(x, v, R, L, bf, bi, b, axis, pi)
        acc[0] += (e1 - e0) - wz * (j1 - j0)


@njit(cache=True, _nrt=False)
def _kick(v, L, F, T, bf, bi, flags, g, h, impulse):
    for b in range(v.shape[0]):
        if bi[b, I_TRANS]:
            inv_m = 1.0 / bf[b, B_MASS]
            for k in range(3):
                v[b, k] += h * F[b, k] * inv_m
                if flags[F_GRAVITY]:
                    v[b, k] += h * g[k]
        for k in range(3):
            L[b, k] += h * T[b, k]
            impulse[b, k] += h * F[b, k]


@njit(cache=True, _nrt=False)
def _gap(x, v, bf, src, a, kind, other):
    """Gap (distance - contact radii) and its rate between body ``a`` and body/rotator ``other``."""
    if kind == 0:
        rx = x[a, 0] - x[other, 0]
        ry = x[a, 1] - x[other, 1]
        rz = x[a, 2] - x[other, 2]
        vx = v[a, 0] - v[other, 0]
        vy = v[a, 1] - v[other, 1]
        vz = v[a, 2] - v[other, 2]
        rad = bf[a, B_RAD] + bf[other, B_RAD]
    else:
        rx = x[a, 0] - src[other, S_AXIS]
        ry = x[a, 1] - src[other, S_AXIS + 1]
        rz = x[a, 2] - src[other, S_AXIS + 2]
        vx, vy, vz = v[a, 0], v[a, 1], v[a, 2]
        rad = bf[a, B_RAD] + src[other, S_RAD]
    d = math.sqrt(rx * rx + ry * ry + rz * rz)
    return d - rad, (rx * vx + ry * vy + rz * vz) / d, d


@njit(cache=True, _nrt=False)
def _events(x, v, bf, bi, src):
    """(contact gap min, its pair, nearest-neighbour distance max) over translating bodies."""
    nb = x.shape[0]
    gmin = 1e300
    ga, gk, go = -1, 0, 0
    far = 0.0
    for a in range(nb):
        if not bi[a, I_TRANS]:
            continue
        nearest = 1e300
        for o in range(nb):
            if o == a:
                continue
            gp, _, d = _gap(x, v, bf, src, a, 0, o)
            if gp < gmin:
                gmin, ga, gk, go = gp, a, 0, o
            nearest = min(nearest, d)
        for s in range(src.shape[0]):
            gp, _, d = _gap(x, v, bf, src, a, 1, s)
            if gp < gmin:
                gmin, ga, gk, go = gp, a, 1, s
            nearest = min(nearest, d)
        if nearest < 1e300:
            far = max(far, nearest)
    return gmin, ga, gk, go, far


@njit(cache=True, _nrt=False)
def _hermite_root(t0, h, g0, d0, g1, d1):
    """Root in [0, 1] of the cubic Hermite interpolant of a gap (values g, rates d)."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        s = 0.5 * (lo + hi)
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        val = h00 * g0 + h10 * h * d0 + h01 * g1 + h11 * h * d1
        if (val > 0.0) == (g0 > 0.0):
            lo = s
        else:
            hi = s
    return t0 + 0.5 * (lo + hi) * h


@njit(cache=True)
def store_sample(n, t, x, v, R, L, budget, out):
    """Copy the state at time ``t`` into sample row ``n`` of ``out``; returns ``n + 1``."""
    out_t, out_x, out_v, out_R, out_L, out_acc, _ = out
    out_t[n] = t
    out_x[n] = x
    out_v[n] = v
    out_R[n] = R
    out_L[n] = L
    out_acc[n] = budget
    return n + 1


@njit(cache=True, _nrt=False)
def health(x, v, L, bf):
    """ST_NONFINITE, ST_BLOWUP (|omega| > 1e9 rad/s or |v| > 1e6 m/s) or ST_OK."""
    big = False
    for b in range(x.shape[0]):
        for k in range(3):
            if not (math.isfinite(x[b, k]) and math.isfinite(v[b, k]) and math.isfinite(L[b, k])):
                return ST_NONFINITE
        wmax = math.sqrt(L[b, 0] ** 2 + L[b, 1] ** 2 + L[b, 2] ** 2) / bf[b, B_I]
        if wmax > 1e9 or abs(v[b, 0]) + abs(v[b, 1]) + abs(v[b, 2]) > 1e6:
            big = True
    return ST_BLOWUP if big else ST_OK


@njit(cache=True, _nrt=False)
def step_event(x, v, xp, vp, bf, bi, src, r_escape, t, h):
    """(status, time) of a contact (Hermite root of the gap over the step) or an escape, else ST_OK."""
    gmin, ga, gk, go, far = _events(x, v, bf, bi, src)
    if ga >= 0 and gmin < 0.0:
        g1, d1, _ = _gap(x, v, bf, src, ga, gk, go)
        g0, d0, _ = _gap(xp, vp, bf, src, ga, gk, go)
        return ST_CONTACT, (_hermite_root(t - h, h, g0, d0, g1, d1) if g0 > 0.0 else t - h)
    if r_escape > 0.0 and far > r_escape:
        return ST_ESCAPE, t
    return ST_OK, math.nan


@njit(cache=True)
def run_rigid(state, t0, h, n_steps, sample_every, weights, args, out, check_events):
    """The general kernel: ``n_steps`` steps of size ``h`` from ``t0`` for any rigid scene.

    ``state = (x, v, R, L)`` is updated in place; ``args`` are the scene's packed kernel arguments
    (:meth:`labkit.sim.compile.CompiledSystem.kernel_args`); ``out = (t, x, v, R, L, budget,
    impulse)`` receives a sample every ``sample_every`` steps (and the first and final states),
    the damping's accumulated share of ``E - wz J_z`` (:func:`damping_flow`) and the magnetic
    impulse. Returns ``(status, steps_done, n_samples, event_time, n_force_evaluations)``.
    """
    x, v, R, L = state
    bf, bi, src, fld, flags, g, axis, r_escape, wz = args
    impulse = out[6]
    nb = x.shape[0]
    F = np.zeros((nb, 3))
    T = np.zeros((nb, 3))
    work = np.empty((2 * nb + 6, 3))
    xp = np.empty((nb, 3))
    vp = np.empty((nb, 3))
    pi = np.empty(3)
    acc = np.zeros(1)
    use_damping = flags[F_DAMPING] != 0
    t = t0
    compute_forces(t, x, R, bf, bi, src, fld, flags, F, T, work)
    n_force = 1
    n_s = store_sample(0, t, x, v, R, L, 0.0, out)
    status = ST_OK
    event_time = math.nan
    steps_done = 0
    for step in range(n_steps):
        if check_events:
            xp[:] = x
            vp[:] = v
        for w in weights:  # one stage: damping, half kick, drift and free rotation, force, half kick
            hw = w * h
            if use_damping:
                damping_flow(x, v, R, L, bf, bi, 0.5 * hw, pi, wz, axis, acc)
            _kick(v, L, F, T, bf, bi, flags, g, 0.5 * hw, impulse)
            for b in range(nb):
                if bi[b, I_TRANS]:
                    for k in range(3):
                        x[b, k] += hw * v[b, k]
                free_rotation(R, L, bf, bi, b, hw, pi)
            t += hw
            compute_forces(t, x, R, bf, bi, src, fld, flags, F, T, work)
            n_force += 1
            _kick(v, L, F, T, bf, bi, flags, g, 0.5 * hw, impulse)
            if use_damping:
                damping_flow(x, v, R, L, bf, bi, 0.5 * hw, pi, wz, axis, acc)
        t = t0 + (step + 1) * h
        steps_done = step + 1
        status = health(x, v, L, bf)
        if status == ST_OK and check_events:
            status, event_time = step_event(x, v, xp, vp, bf, bi, src, r_escape, t, h)
        elif status != ST_OK:
            event_time = t
        if status != ST_OK:
            break
        if (step + 1) % sample_every == 0:
            n_s = store_sample(n_s, t, x, v, R, L, acc[0], out)
    if status != ST_OK or steps_done % sample_every != 0:
        n_s = store_sample(n_s, t, x, v, R, L, acc[0], out)
    return status, steps_done, n_s, event_time, n_force


@njit(cache=True, _nrt=False)
def reduced_acceleration(form, y, t, jc, js, omega, phase):
    """Eq. 5.484 (form 0): ``-J_S sin y - J_C cos(wt) cos y``; Eq. 5.56 (form 1): ``J_C sin(y - wt)``."""
    th = omega * t + phase
    if form == 0:
        return -js * math.sin(y) - jc * math.cos(th) * math.cos(y)
    return jc * math.sin(y - th)


@njit(cache=True)
def run_reduced(
    form, jc, js, omega, phase, y, yd, t0, h, n_steps, sample_every, weights, out_t, out_y, out_yd
):
    """Splitting integration of the one-DoF reduced forms; returns (status, steps, samples, n_force)."""
    t = t0
    a = reduced_acceleration(form, y, t, jc, js, omega, phase)
    n_force = 1
    out_t[0] = t
    out_y[0] = y
    out_yd[0] = yd
    n_s = 1
    status = 0
    steps_done = 0
    for step in range(n_steps):
        for w in weights:
            hw = w * h
            yd += 0.5 * hw * a
            y += hw * yd
            t += hw
            a = reduced_acceleration(form, y, t, jc, js, omega, phase)
            n_force += 1
            yd += 0.5 * hw * a
        t = t0 + (step + 1) * h
        steps_done = step + 1
        if not (math.isfinite(y) and math.isfinite(yd)):
            status = 1
            break
        if (step + 1) % sample_every == 0:
            out_t[n_s] = t
            out_y[n_s] = y
            out_yd[n_s] = yd
            n_s += 1
    if status != 0 or steps_done % sample_every != 0:
        out_t[n_s] = t
        out_y[n_s] = y
        out_yd[n_s] = yd
        n_s += 1
    return status, steps_done, n_s, n_force
