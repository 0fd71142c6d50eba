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
into ``args`` once (:func:`labkit.sim.integrators.rigid_rhs.pack_args`); CyRK copies ``args``
into its solver and hands that copy to every call, so the scratch space is private to one solve.
``args[COUNT]`` counts calls. CyRK's numba solver has no events: contact and escape are checked
on the samples.
"""

from __future__ import annotations

import ctypes
import math
import sys
import time

import numpy as np
from numba import carray, cfunc, types

from labkit.sim.compile import CompiledSystem
from labkit.sim.integrators.kernels import I_TRANS
from labkit.sim.integrators.raw_run import RawRun, SimulationError, check_memory
from labkit.sim.integrators.reference import sample_times, tolerance_scale
from labkit.sim.integrators.rigid_rhs import (
    COUNT,
    FLAGS_WIDTH,
    FLD_WIDTH,
    HEADER,
    NB,
    NS,
    STRIDE,
    pack_args,
    rigid_derivative,
)


def available() -> bool:
    """Whether CyRK (the ``bench`` extra) is installed."""
    try:
        import CyRK  # noqa: F401
    except ImportError:
        return False
    return True


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
