"""The rigid-body right-hand side compiled once for every scene (numba), used by the scipy
reference (:mod:`.reference`) and the compiled DOP853 (:mod:`.compiled_reference`).

The state per body is position, velocity, rotation matrix (9) and lab angular momentum
(:data:`STRIDE` numbers), followed by the time integral of each body's magnetic force (3 per
body) and the damping's share of ``E - w J_z`` (1). The scene's parameters and the scratch
space are packed into one float array ``args`` once (:func:`pack_args`); ``args[COUNT]`` counts
calls.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from labkit.sim.compile import CompiledSystem
from labkit.sim.integrators.kernels import B_CLIN, B_CROT, B_MASS, I_TRANS, compute_forces

STRIDE = 18
#: header of ``args``: body count, source count, gravity (3), wz, axis point (3), call count
NB, NS, G, WZ, AXIS, COUNT, HEADER = 0, 1, 2, 5, 6, 9, 10
FLD_WIDTH, FLAGS_WIDTH = 5, 6


def _sizes(nb: int, ns: int) -> tuple[int, ...]:
    """Offsets of bf, bi, src, fld, flags, F, T, work, X, R, L and the total length."""
    sizes = [nb * 13, nb * 4, ns * 12, FLD_WIDTH, FLAGS_WIDTH, nb * 3, nb * 3, (2 * nb + 6) * 3,
             nb * 3, nb * 9, nb * 3]
    offsets = [HEADER]
    for s in sizes:
        offsets.append(offsets[-1] + s)
    return tuple(offsets)


def pack_args(system: CompiledSystem) -> np.ndarray:
    """The scene's parameters and scratch space as one float array (the layout of :func:`_sizes`)."""
    nb, ns = system.bf.shape[0], system.src.shape[0]
    off = _sizes(nb, ns)
    args = np.zeros(off[-1])
    args[NB], args[NS] = nb, ns
    args[G:G + 3] = system.g
    args[WZ] = system.wz
    args[AXIS:AXIS + 3] = system.axis
    for k, part in enumerate((system.bf, system.bi, system.src, system.fld, system.flags)):
        args[off[k]:off[k + 1]] = np.asarray(part, dtype=float).ravel()
    return args


@njit(cache=True)
def rigid_derivative(t, y, dy, a):
    """``dy = f(t, y)`` of the rigid-body state (see the module docstring); ``a`` is the packed
    args (parameters and scratch space; nothing is allocated)."""
    nb, ns = int(a[NB]), int(a[NS])
    o_bf = HEADER
    o_bi = o_bf + nb * 13
    o_src = o_bi + nb * 4
    o_fld = o_src + ns * 12
    o_flags = o_fld + FLD_WIDTH
    o_f = o_flags + FLAGS_WIDTH
    o_t = o_f + nb * 3
    o_work = o_t + nb * 3
    o_x = o_work + (2 * nb + 6) * 3
    o_r = o_x + nb * 3
    o_l = o_r + nb * 9
    bf = a[o_bf:o_bi].reshape((nb, 13))
    bi = a[o_bi:o_src].reshape((nb, 4))
    src = a[o_src:o_fld].reshape((ns, 12))
    fld = a[o_fld:o_flags]
    flags = a[o_flags:o_f]
    force = a[o_f:o_t].reshape((nb, 3))
    torque = a[o_t:o_work].reshape((nb, 3))
    work = a[o_work:o_x].reshape((2 * nb + 6, 3))
    x = a[o_x:o_r].reshape((nb, 3))
    rot = a[o_r:o_l].reshape((nb, 3, 3))
    ang = a[o_l:o_l + nb * 3].reshape((nb, 3))
    a[COUNT] += 1.0
    for b in range(nb):
        s = b * STRIDE
        for k in range(3):
            x[b, k] = y[s + k]
            ang[b, k] = y[s + 15 + k]
        for k in range(9):
            rot[b, k // 3, k % 3] = y[s + 6 + k]
    compute_forces(t, x, rot, bf, bi, src, fld, flags, force, torque, work)
    budget = 0.0
    jz_rate = 0.0
    for b in range(nb):
        s = b * STRIDE
        # omega = R I^-1 R^T L
        p0 = rot[b, 0, 0] * ang[b, 0] + rot[b, 1, 0] * ang[b, 1] + rot[b, 2, 0] * ang[b, 2]
        p1 = rot[b, 0, 1] * ang[b, 0] + rot[b, 1, 1] * ang[b, 1] + rot[b, 2, 1] * ang[b, 2]
        p2 = rot[b, 0, 2] * ang[b, 0] + rot[b, 1, 2] * ang[b, 1] + rot[b, 2, 2] * ang[b, 2]
        p0, p1, p2 = p0 / bf[b, 1], p1 / bf[b, 2], p2 / bf[b, 3]
        w0 = rot[b, 0, 0] * p0 + rot[b, 0, 1] * p1 + rot[b, 0, 2] * p2
        w1 = rot[b, 1, 0] * p0 + rot[b, 1, 1] * p1 + rot[b, 1, 2] * p2
        w2 = rot[b, 2, 0] * p0 + rot[b, 2, 1] * p1 + rot[b, 2, 2] * p2
        mass, c_lin, c_rot = bf[b, B_MASS], bf[b, B_CLIN], bf[b, B_CROT]
        moves = bi[b, I_TRANS] != 0.0
        v0, v1, v2 = y[s + 3], y[s + 4], y[s + 5]
        for k in range(3):
            if moves:
                dy[s + k] = y[s + 3 + k]
                dy[s + 3 + k] = force[b, k] / mass + a[G + k] - c_lin / mass * y[s + 3 + k]
            else:
                dy[s + k] = 0.0
                dy[s + 3 + k] = 0.0
        for j in range(3):  # dR/dt = [omega]x R
            r0, r1, r2 = rot[b, 0, j], rot[b, 1, j], rot[b, 2, j]
            dy[s + 6 + j] = w1 * r2 - w2 * r1
            dy[s + 9 + j] = w2 * r0 - w0 * r2
            dy[s + 12 + j] = w0 * r1 - w1 * r0
        dy[s + 15] = torque[b, 0] - c_rot * w0
        dy[s + 16] = torque[b, 1] - c_rot * w1
        dy[s + 17] = torque[b, 2] - c_rot * w2
        for k in range(3):
            dy[nb * STRIDE + 3 * b + k] = force[b, k]
        cl = c_lin if moves else 0.0
        rx, ry = x[b, 0] - a[AXIS], x[b, 1] - a[AXIS + 1]
        jz_rate += -cl * (rx * v1 - ry * v0) - c_rot * w2
        budget += -cl * (v0 * v0 + v1 * v1 + v2 * v2) - c_rot * (w0 * w0 + w1 * w1 + w2 * w2)
    dy[nb * STRIDE + 3 * nb] = budget - a[WZ] * jz_rate
