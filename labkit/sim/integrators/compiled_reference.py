"""A compiled DOP853 peer: CyRK's C++ DOP853 with a numba-compiled right-hand side.

The fair comparison for labkit's splittings (docs/explanation/numerics.md, "Against a compiled DOP853"):
the same equations, state and tolerances as the scipy reference (:mod:`.reference`), but
neither the solver nor the right-hand side runs Python. The state per body is position,
velocity, rotation matrix (9) and lab angular momentum, followed by the time integral of each
body's magnetic force (3 per body) and the damping's share of ``E - w J_z`` (1); absolute
tolerances are ``rtol`` times the scale of each component, exactly as the scipy reference.

CyRK (an optional ``bench`` extra: ``pip install labkit[bench]``) calls the right-hand side
through a C function pointer ``void f(double* dy, double t, double* y, double* args)``. One
right-hand side serves every scene: the scene's parameters and the scratch space are packed
into ``args`` once (:func:`pack_args`); CyRK copies ``args`` into its solver and hands that
copy to every call, so the scratch space is private to one solve. ``args[COUNT]`` counts
calls. CyRK's numba solver has no events: contact and escape are checked on the samples.
"""

from __future__ import annotations

import ctypes
import math
import sys
import time

import numpy as np
from numba import carray, cfunc, njit, types

from labkit.sim.compile import CompiledSystem
from labkit.sim.integrators import RawRun, SimulationError, check_memory
from labkit.sim.integrators.kernels import B_CLIN, B_CROT, B_MASS, I_TRANS, compute_forces
from labkit.sim.integrators.reference import STRIDE, sample_times, tolerance_scale

#: header of ``args``: body count, source count, gravity (3), wz, axis point (3), call count
NB, NS, G, WZ, AXIS, COUNT, HEADER = 0, 1, 2, 5, 6, 9, 10
FLD_WIDTH, FLAGS_WIDTH = 5, 6


def available() -> bool:
    """Whether CyRK (the ``bench`` extra) is installed."""
    try:
        import CyRK  # noqa: F401
    except ImportError:
        return False
    return True


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


_SIGNATURE = types.void(types.CPointer(types.float64), types.float64, types.CPointer(types.float64),
                        types.CPointer(types.float64))
_RHS = None


def _rhs_address() -> tuple[int, float]:
    """Address of the C right-hand side (compiled or loaded once per process; sizes are read from
    args) and the seconds that took on this call (0 after the first)."""
    global _RHS
    start = time.perf_counter()
    if _RHS is None:

        @cfunc(_SIGNATURE, cache=True)
        def rhs(dy_ptr, t, y_ptr, args_ptr):  # pragma: no cover - runs inside CyRK
            head = carray(args_ptr, (HEADER,))
            nb, ns = int(head[NB]), int(head[NS])
            n = nb * STRIDE + 3 * nb + 1
            total = HEADER + nb * 13 + nb * 4 + ns * 12 + FLD_WIDTH + FLAGS_WIDTH + nb * 21 + (2 * nb + 6) * 3
            rigid_derivative(t, carray(y_ptr, (n,)), carray(dy_ptr, (n,)), carray(args_ptr, (total,)))

        _RHS = rhs
        return _RHS.address, time.perf_counter() - start
    return _RHS.address, 0.0


def _solve(system: CompiledSystem, y0, t_span, t_eval, rtol: float, atols: np.ndarray, args: np.ndarray):
    """Run CyRK's C++ DOP853 through its C API; returns (t, y (n, len(y0)), success, message, calls,
    seconds spent compiling or loading the right-hand side)."""
    start = time.perf_counter()
    first = "CyRK.nb.numba_solver" not in sys.modules
    try:
        from CyRK.nb import numba_solver as cy
    except ImportError as exc:  # not installed, or a CPU its wheel cannot run on (CyRK says which)
        raise SimulationError(
            f"the compiled DOP853 needs CyRK (pip install 'labkit[bench]'): {exc}"
        ) from None
    address, compile_s = _rhs_address()
    if first:  # importing CyRK's numba layer is a one-off cost, like compiling the right-hand side
        compile_s = time.perf_counter() - start
    y0 = np.ascontiguousarray(y0, dtype=float)
    t_eval = np.ascontiguousarray(t_eval, dtype=float)
    rtols = np.array([rtol])
    atols = np.ascontiguousarray(atols, dtype=float)
    method = 5  # ODEMethod DOP853 (CyRK.nb.numba_solver.get_method_str)
    ptr = cy.c_numba_cysolve_ivp(
        address, float(t_span[0]), float(t_span[1]), y0.ctypes.data, y0.size, method, 0, 0,
        args.ctypes.data, args.size * 8, 0, 8000, False, t_eval.ctypes.data, t_eval.size, None, None, 0,
        rtols.ctypes.data, rtols.size, atols.ctypes.data, atols.size, float(np.finfo(float).max / 2),
        0.0, True,
    )
    if not ptr:
        raise SimulationError("CyRK returned no solution (out of memory?)")
    try:
        success = bool(cy.c_get_success(ptr))
        size, width = cy.c_get_size(ptr), cy.c_get_num_dy(ptr)
        t = np.ctypeslib.as_array(cy.c_get_t_ptr(ptr), (size,)).copy() if size else np.empty(0)
        y = np.ctypeslib.as_array(cy.c_get_y_ptr(ptr), (size, width)).copy() if size else np.empty((0, width))
        stored = ctypes.cast(cy.c_get_args_ptr(ptr), ctypes.POINTER(ctypes.c_double))
        calls = int(stored[COUNT])
        buf = np.zeros(256, dtype=np.uint8)
        cy.c_get_msg_buf(ptr, buf.ctypes.data, buf.size)
        message = bytes(buf).split(b"\0", 1)[0].decode(errors="replace")
    finally:
        cy.c_free(ptr)
    return t, y, success, message, calls, compile_s


def _sample_events(system: CompiledSystem, x: np.ndarray) -> tuple[int, int]:
    """(status, first sample index) of contact (3) or escape (4) seen on the samples; (0, -1) else."""
    bf, bi, src = system.bf, system.bi, system.src
    nb = bf.shape[0]
    for i in range(x.shape[0]):
        for a in range(nb):
            if not bi[a, I_TRANS]:
                continue
            gaps = [np.linalg.norm(x[i, a] - x[i, b]) - bf[a, 12] - bf[b, 12] for b in range(nb) if b != a]
            dists = [np.linalg.norm(x[i, a] - src[s, 8:11]) for s in range(src.shape[0])]
            gaps += [d - bf[a, 12] - src[s, 11] for s, d in enumerate(dists)]
            if gaps and min(gaps) < 0.0:
                return 3, i
            nearest = min(dists + [np.linalg.norm(x[i, a] - x[i, b]) for b in range(nb) if b != a],
                          default=0.0)
            if system.r_escape and nearest > system.r_escape:
                return 4, i
    return 0, -1


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
    """Integrate with CyRK's compiled DOP853; samples at exact multiples of ``T / samples_per_period``."""
    if system.reduced is not None or system.kind != "rigid":
        raise SimulationError(f"{name}: the compiled DOP853 integrates rigid-body scenes only "
                              f"({system.scene.name} compiles to {system.kind})")
    t_end = t0 + cycles * system.period
    n = int(round(cycles * samples_per_period))
    t_eval = sample_times(t0, t_end, n, system.period / samples_per_period, decimate)
    nb = system.bf.shape[0]
    check_memory(n + 2, nb)
    state0 = np.concatenate([system.x0, system.v0, system.R0.reshape(nb, 9), system.L0], axis=1).ravel()
    y0 = np.concatenate([state0, np.zeros(3 * nb + 1)])
    scale = tolerance_scale(system)
    atols = np.where(np.isfinite(scale), rtol * scale, 1e300)
    args = pack_args(system)
    t, full, success, message, calls, compile_s = _solve(system, y0, (t0, t_end), t_eval, rtol, atols, args)
    setting = {"method": "CyRK " + method, "rtol": rtol, "samples_per_period": samples_per_period}
    ys = full[:, : nb * STRIDE].reshape(-1, nb, STRIDE)
    status, event_time = (0 if success else 5), math.nan
    if not np.all(np.isfinite(ys)):
        status = 1
    elif success:
        code, i = _sample_events(system, ys[..., 0:3])
        if code:
            status, event_time = code, float(t[i])
            ys, t, full = ys[: i + 1], t[: i + 1], full[: i + 1]
    x, v, R, L = ys[..., 0:3], ys[..., 3:6], ys[..., 6:15].reshape(-1, nb, 3, 3), ys[..., 15:18]
    impulse = full[-1, nb * STRIDE: nb * STRIDE + 3 * nb].reshape(nb, 3) if len(full) else np.zeros((nb, 3))
    return RawRun(name, setting, status, event_time, calls, t, x=x.copy(), v=v.copy(), R=R.copy(),
                  L=L.copy(), impulse=impulse.copy(), budget=full[:, -1].copy(), message=message,
                  extra={"compile_s": compile_s})
