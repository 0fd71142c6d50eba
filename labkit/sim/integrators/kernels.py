"""Compiled (numba, cached) physics kernels of the simulator: point-dipole field, force and
torque (Eq. 4.1-4.4), driven rotators (Eq. 5.25), uniform fields (Eq. 5.21, 5.481), forces and
torques on every body, energies and momenta for the invariants.

They are self-contained on purpose (the step loop calls them millions of times); the tests
check them against :mod:`labkit.model.dipole`. Helpers that never allocate are compiled with
``_nrt=False``: numba's reference counting of array arguments otherwise costs ~20 ns per array
per call, which tripled the step cost (measured: a kick went from 195 ns to 6 ns).

Parameter layout (filled by :mod:`labkit.sim.compile`):

* ``bf[b]``: mass, I1, I2, I3 (principal), m (3, principal frame), offset (3), c_lin, c_rot,
  contact radius
* ``bi[b]``: translates, free-rotation kind (0 exact symmetric top, 1 DLM), has dipole,
  force evaluated
* ``src[s]``: moment, tilt, omega, phase, ramp, shift (3, rotator frame), axis point (3),
  contact radius
* ``fld``: kind (0 none, 1 rotating/static, 2 oscillating), B_c, B_s, omega, phase
* ``flags``: field, sources, pairs, gravity, damping, forces
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

K_M = 1e-7  # mu0 / 4 pi (T m / A)

# column indices
B_MASS, B_I, B_M, B_OFF, B_CLIN, B_CROT, B_RAD = 0, 1, 4, 7, 10, 11, 12
BF_WIDTH = 13
I_TRANS, I_FREE, I_DIPOLE, I_FORCE = 0, 1, 2, 3
S_MOM, S_TILT, S_OMEGA, S_PHASE, S_RAMP, S_SHIFT, S_AXIS, S_RAD = 0, 1, 2, 3, 4, 5, 8, 11
SRC_WIDTH = 12
F_FIELD, F_SOURCES, F_PAIRS, F_GRAVITY, F_DAMPING, F_FORCES = 0, 1, 2, 3, 4, 5


@njit(cache=True, _nrt=False)
def dipole_field(mx, my, mz, rx, ry, rz):
    """B (T) of dipole ``m`` at displacement ``r`` from it (Eq. 4.1), as a 3-tuple."""
    d2 = rx * rx + ry * ry + rz * rz
    d = math.sqrt(d2)
    inv3 = K_M / (d2 * d)
    mr = 3.0 * (mx * rx + my * ry + mz * rz) / d2
    return inv3 * (mr * rx - mx), inv3 * (mr * ry - my), inv3 * (mr * rz - mz)


@njit(cache=True, _nrt=False)
def dipole_force_torque(ax, ay, az, bx, by, bz, rx, ry, rz):
    """Force and torque on dipole ``b`` from ``a``; ``r`` from a to b (Eq. 4.2, 4.3).

    Returns the 6-tuple ``(Fx, Fy, Fz, tau_x, tau_y, tau_z)``; the torque is about b's centre.
    """
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
    # tau = 3 (a.u)(b x u) + a x b
    tx = ct * (3.0 * ra * (by * uz - bz * uy) + ay * bz - az * by)
    ty = ct * (3.0 * ra * (bz * ux - bx * uz) + az * bx - ax * bz)
    tz = ct * (3.0 * ra * (bx * uy - by * ux) + ax * by - ay * bx)
    return fx, fy, fz, tx, ty, tz


@njit(cache=True, _nrt=False)
def source_angle(src, s, t):
    return src[s, S_PHASE] + src[s, S_OMEGA] * t + 0.5 * src[s, S_RAMP] * t * t


@njit(cache=True, _nrt=False)
def source_state(src, s, t):
    """Moment (Eq. 5.25) and position of driven rotator ``s`` at ``t``: (mx, my, mz, px, py, pz)."""
    th = source_angle(src, s, t)
    c, sn = math.cos(th), math.sin(th)
    mom, g = src[s, S_MOM], src[s, S_TILT]
    m0y, m0z = -mom * math.cos(g), mom * math.sin(g)
    sx, sy, sz = src[s, S_SHIFT], src[s, S_SHIFT + 1], src[s, S_SHIFT + 2]
    return (
        -sn * m0y,
        c * m0y,
        m0z,
        src[s, S_AXIS] + c * sx - sn * sy,
        src[s, S_AXIS + 1] + sn * sx + c * sy,
        src[s, S_AXIS + 2] + sz,
    )


@njit(cache=True, _nrt=False)
def uniform_field(fld, t):
    """Uniform field at ``t``: rotating (Eq. 5.21; static if omega = 0) or oscillating (Eq. 5.481)."""
    th = fld[4] + fld[3] * t
    if fld[0] == 1.0:
        return -fld[1] * math.sin(th), fld[1] * math.cos(th), fld[2]
    if fld[0] == 2.0:
        return 0.0, fld[1] * math.cos(th), fld[2]
    return 0.0, 0.0, 0.0


@njit(cache=True, _nrt=False)
def body_dipoles(R, bf, bi, x, work):
    """Lab moment (rows 0..nb-1 of ``work``) and position (rows nb..2nb-1) of every dipole."""
    nb = x.shape[0]
    for b in range(nb):
        if not bi[b, I_DIPOLE]:
            continue
        for i in range(3):
            acc_m = 0.0
            acc_p = 0.0
            for j in range(3):
                acc_m += R[b, i, j] * bf[b, B_M + j]
                acc_p += R[b, i, j] * bf[b, B_OFF + j]
            work[b, i] = acc_m
            work[nb + b, i] = x[b, i] + acc_p


@njit(cache=True, _nrt=False)
def _add(b, f, x, work, force, torque):
    """Add force ``f[0:3]`` and dipole torque ``f[3:6]`` on body b; torque about the CM."""
    nb = x.shape[0]
    ox = work[nb + b, 0] - x[b, 0]
    oy = work[nb + b, 1] - x[b, 1]
    oz = work[nb + b, 2] - x[b, 2]
    force[b, 0] += f[0]
    force[b, 1] += f[1]
    force[b, 2] += f[2]
    torque[b, 0] += f[3] + oy * f[2] - oz * f[1]
    torque[b, 1] += f[4] + oz * f[0] - ox * f[2]
    torque[b, 2] += f[5] + ox * f[1] - oy * f[0]


def workspace(nb: int) -> np.ndarray:
    """Scratch space for :func:`compute_forces` (allocate once per run)."""
    return np.empty((2 * nb + 6, 3))


@njit(cache=True, _nrt=False)
def compute_forces(t, x, R, bf, bi, src, fld, flags, force, torque, work):
    """Magnetic force and torque (about the CM) on every body at time ``t``.

    Only the parts the scene has are evaluated (uniform field, driven rotators, body pairs).
    ``work`` is scratch space from :func:`workspace`.
    """
    nb = x.shape[0]
    for b in range(nb):
        for k in range(3):
            force[b, k] = 0.0
            torque[b, k] = 0.0
    body_dipoles(R, bf, bi, x, work)
    if flags[F_FIELD]:
        bx, by, bz = uniform_field(fld, t)
        for b in range(nb):
            if bi[b, I_DIPOLE]:
                mx, my, mz = work[b, 0], work[b, 1], work[b, 2]
                torque[b, 0] += my * bz - mz * by
                torque[b, 1] += mz * bx - mx * bz
                torque[b, 2] += mx * by - my * bx
    if flags[F_SOURCES]:
        for s in range(src.shape[0]):
            smx, smy, smz, spx, spy, spz = source_state(src, s, t)
            for b in range(nb):
                if not bi[b, I_DIPOLE]:
                    continue
                f = dipole_force_torque(
                    smx,
                    smy,
                    smz,
                    work[b, 0],
                    work[b, 1],
                    work[b, 2],
                    work[nb + b, 0] - spx,
                    work[nb + b, 1] - spy,
                    work[nb + b, 2] - spz,
                )
                _add(b, f, x, work, force, torque)
    if flags[F_PAIRS]:
        for a in range(nb):
            if not bi[a, I_DIPOLE]:
                continue
            for b in range(a + 1, nb):
                if not bi[b, I_DIPOLE]:
                    continue
                rx = work[nb + b, 0] - work[nb + a, 0]
                ry = work[nb + b, 1] - work[nb + a, 1]
                rz = work[nb + b, 2] - work[nb + a, 2]
                f = dipole_force_torque(
                    work[a, 0], work[a, 1], work[a, 2], work[b, 0], work[b, 1], work[b, 2], rx, ry, rz
                )
                _add(b, f, x, work, force, torque)
                # on a: b's field, r from b to a (force is the opposite, Eq. 4.2 is symmetric)
                f = dipole_force_torque(
                    work[b, 0], work[b, 1], work[b, 2], work[a, 0], work[a, 1], work[a, 2], -rx, -ry, -rz
                )
                _add(a, f, x, work, force, torque)


@njit(cache=True, _nrt=False)
def potential_energy(t, x, R, bf, bi, src, fld, flags, g, work):
    """Magnetic (-m.B, pairs once) plus gravitational (-M g.x) potential energy (J)."""
    nb = x.shape[0]
    body_dipoles(R, bf, bi, x, work)
    u = 0.0
    for b in range(nb):
        if bi[b, I_TRANS] and flags[F_GRAVITY]:
            u -= bf[b, B_MASS] * (g[0] * x[b, 0] + g[1] * x[b, 1] + g[2] * x[b, 2])
        if not bi[b, I_DIPOLE]:
            continue
        mx, my, mz = work[b, 0], work[b, 1], work[b, 2]
        px, py, pz = work[nb + b, 0], work[nb + b, 1], work[nb + b, 2]
        if flags[F_FIELD]:
            bx, by, bz = uniform_field(fld, t)
            u -= mx * bx + my * by + mz * bz
        if flags[F_SOURCES]:
            for s in range(src.shape[0]):
                smx, smy, smz, spx, spy, spz = source_state(src, s, t)
                bx, by, bz = dipole_field(smx, smy, smz, px - spx, py - spy, pz - spz)
                u -= mx * bx + my * by + mz * bz
        if flags[F_PAIRS]:
            for a in range(b + 1, nb):
                if not bi[a, I_DIPOLE]:
                    continue
                bx, by, bz = dipole_field(
                    work[a, 0],
                    work[a, 1],
                    work[a, 2],
                    px - work[nb + a, 0],
                    py - work[nb + a, 1],
                    pz - work[nb + a, 2],
                )
                u -= mx * bx + my * by + mz * bz
    return u


@njit(cache=True, _nrt=False)
def lab_angular_velocity(R, bf, b, L, out):
    """Omega = R I^-1 R^T L for body ``b``."""
    pi0 = R[b, 0, 0] * L[b, 0] + R[b, 1, 0] * L[b, 1] + R[b, 2, 0] * L[b, 2]
    pi1 = R[b, 0, 1] * L[b, 0] + R[b, 1, 1] * L[b, 1] + R[b, 2, 1] * L[b, 2]
    pi2 = R[b, 0, 2] * L[b, 0] + R[b, 1, 2] * L[b, 1] + R[b, 2, 2] * L[b, 2]
    w0 = pi0 / bf[b, B_I]
    w1 = pi1 / bf[b, B_I + 1]
    w2 = pi2 / bf[b, B_I + 2]
    for i in range(3):
        out[i] = R[b, i, 0] * w0 + R[b, i, 1] * w1 + R[b, i, 2] * w2


@njit(cache=True)
def invariant_terms(t, x, v, R, L, bf, bi, src, fld, flags, g, axis, out):
    """Per-sample terms: out = [kinetic, potential, J_z about ``axis`` line, P(3), J(3)]."""
    nb = x.shape[0]
    w = np.empty(3)
    work = np.empty((2 * nb + 6, 3))
    kin = 0.0
    jz = 0.0
    for k in range(6):
        out[3 + k] = 0.0
    for b in range(nb):
        lab_angular_velocity(R, bf, b, L, w)
        kin += 0.5 * (w[0] * L[b, 0] + w[1] * L[b, 1] + w[2] * L[b, 2])
        m = bf[b, B_MASS]
        if bi[b, I_TRANS]:
            kin += 0.5 * m * (v[b, 0] ** 2 + v[b, 1] ** 2 + v[b, 2] ** 2)
            rx, ry = x[b, 0] - axis[0], x[b, 1] - axis[1]
            jz += m * (rx * v[b, 1] - ry * v[b, 0])
            for k in range(3):
                out[3 + k] += m * v[b, k]
            out[6] += m * (x[b, 1] * v[b, 2] - x[b, 2] * v[b, 1])
            out[7] += m * (x[b, 2] * v[b, 0] - x[b, 0] * v[b, 2])
            out[8] += m * (x[b, 0] * v[b, 1] - x[b, 1] * v[b, 0])
        jz += L[b, 2]
        for k in range(3):
            out[6 + k] += L[b, k]
    out[0] = kin
    out[1] = potential_energy(t, x, R, bf, bi, src, fld, flags, g, work)
    out[2] = jz


@njit(cache=True)
def invariants_over_samples(ts, xs, vs, Rs, Ls, bf, bi, src, fld, flags, g, axis):
    n = ts.shape[0]
    res = np.empty((n, 9))
    row = np.empty(9)
    for i in range(n):
        invariant_terms(ts[i], xs[i], vs[i], Rs[i], Ls[i], bf, bi, src, fld, flags, g, axis, row)
        for k in range(9):
            res[i, k] = row[k]
    return res
