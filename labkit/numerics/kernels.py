"""Fast kernels for batches of one-body uniform-field scenes (sweeps and stability maps).

The scene family is the paper's Sec. 5.1-5.1.6 problem: an axisymmetric body (radial moment
``I_R``, axial ``I_A``, dipole on the symmetry axis) turning about its fixed CM in the uniform
field ``B = B_C [-sin th, cos th, 0] + B_S z``, ``th = omega t + phase`` (Eq. 5.21). It is
integrated **nondimensionally** (docs/explanation/numerics-notes.md#scaling): time ``s = omega t``, angular
momentum
``l = L / (I_R omega)``, torque coefficients ``j_C = tau_C / (I_R omega^2)`` and
``j_S = tau_S / (I_R omega^2)`` (Eq. 5.22), inertia ratio ``a = I_A / I_R``. So a 5 mg fragment
at 11 000 rad/s and a 7 g floator at 250 rad/s with the same ``j`` are the same ODE.

The scheme is the simulator's default: Suzuki's 5-stage composition of kick(h/2) -
exact symmetric-top free rotation(h) - kick(h/2) with ``h = 2 pi / N`` (one drive period is
``N`` steps), so every sample falls on an exact multiple of ``T / samples_per_period``.

Two implementations of the same arithmetic, measured against each other by
``labkit bench sim`` (``kernel_timings``):

* :func:`run_batch_numba`: a numba kernel (``cache=True``, compiled once to disk) looping over
  the batch, one trajectory at a time;
* :func:`run_batch_numpy`: vectorised numpy over the batch (structure of arrays, lock-step).

Both return the stroboscopic zenith angle of the dipole (Eq. 5.7's ``phi``) and the
Jacobi-type invariant ``K = T + U - omega J_z`` (docs/explanation/numerics-notes.md#the-jacobi-constant) in
units of ``I_R omega^2``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from labkit.sim.integrators.splitting import COMPOSITIONS, rotate_axis_angle, rotate_body_columns


@dataclass
class BatchSpec:
    """Nondimensional parameters of a batch of one-body uniform-field scenes (arrays of length B).

    ``l0`` (B, 3) is the initial lab angular momentum over ``I_R omega``; ``R0`` (B, 3, 3) maps
    body to lab (the dipole is body z).
    """

    j_c: np.ndarray
    j_s: np.ndarray
    inertia_ratio: np.ndarray
    phase: np.ndarray
    R0: np.ndarray
    l0: np.ndarray

    @property
    def size(self) -> int:
        return int(np.asarray(self.j_c).shape[0])


@dataclass
class BatchResult:
    """Stroboscopic samples: ``zenith`` and ``jacobi`` (B, n_samples) at ``s = k 2 pi / samples``."""

    zenith: np.ndarray
    jacobi: np.ndarray
    samples_per_period: int


def weights_for(method: str = "suzuki4") -> np.ndarray:
    """Stage weights of a symmetric composition shared with :mod:`labkit.sim` (default Suzuki-4)."""
    return np.ascontiguousarray(COMPOSITIONS[method][0], dtype=float)


# --------------------------------------------------------------------------- numba version


@njit(cache=True)
def _jacobi(R, l, a, jc, js, s, phase):
    """K = kinetic + (-m.B) - l_z in units of I_R omega^2 (drive at unit speed, Eq. 5.21)."""
    pi0 = R[0, 0] * l[0] + R[1, 0] * l[1] + R[2, 0] * l[2]
    pi1 = R[0, 1] * l[0] + R[1, 1] * l[1] + R[2, 1] * l[2]
    pi2 = R[0, 2] * l[0] + R[1, 2] * l[1] + R[2, 2] * l[2]
    kin = 0.5 * (pi0 * pi0 + pi1 * pi1 + pi2 * pi2 / a)
    th = s + phase
    pot = -(-jc * math.sin(th) * R[0, 2] + jc * math.cos(th) * R[1, 2] + js * R[2, 2])
    return kin + pot - l[2]


@njit(cache=True)
def _torque_nb(R, jc, js, th):
    """Torque u x b on the unit dipole u = R e_z (units I_R omega^2), Eq. 5.21-5.22."""
    bx = -jc * math.sin(th)
    by = jc * math.cos(th)
    ux, uy, uz = R[0, 2], R[1, 2], R[2, 2]
    return uy * js - uz * by, uz * bx - ux * js, ux * by - uy * bx


@njit(cache=True)
def _one(R, l, a, jc, js, phase, n_periods, n_steps, every, weights, zen, jac):
    h = 2.0 * math.pi / n_steps
    s = 0.0
    k = 0
    zen[k] = math.acos(min(1.0, max(-1.0, R[2, 2])))
    jac[k] = _jacobi(R, l, a, jc, js, s, phase)
    inv_a1 = 1.0 / a - 1.0
    tx, ty, tz = _torque_nb(R, jc, js, s + phase)
    for period in range(n_periods):
        for step in range(n_steps):
            for w in weights:
                hw = w * h
                # kick(hw/2) with the torque u x b at the current time (shared with the
                # previous stage's closing kick: same state, same time)
                l[0] += 0.5 * hw * tx
                l[1] += 0.5 * hw * ty
                l[2] += 0.5 * hw * tz
                # exact free rotation of a symmetric top (I_R = 1, I_A = a)
                l3 = R[0, 2] * l[0] + R[1, 2] * l[1] + R[2, 2] * l[2]
                c = hw * l3 * inv_a1
                if c != 0.0:
                    rotate_body_columns(R, 2, c)
                ln = math.sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2])
                if ln > 0.0:
                    rotate_axis_angle(R, l[0] / ln, l[1] / ln, l[2] / ln, hw * ln)
                s += hw
                tx, ty, tz = _torque_nb(R, jc, js, s + phase)
                l[0] += 0.5 * hw * tx
                l[1] += 0.5 * hw * ty
                l[2] += 0.5 * hw * tz
            s = 2.0 * math.pi * (period + (step + 1.0) / n_steps)
            if (step + 1) % every == 0:
                k += 1
                zen[k] = math.acos(min(1.0, max(-1.0, R[2, 2])))
                jac[k] = _jacobi(R, l, a, jc, js, s, phase)


@njit(cache=True, nogil=True)
def _batch(R0, l0, a, jc, js, phase, n_periods, n_steps, every, weights, zen, jac):
    # nogil: the batch writes only its own arrays, so the GIL is released while it runs and a
    # multi-threaded Dask worker (or its event loop) is not held up by it
    for b in range(R0.shape[0]):
        R = R0[b].copy()
        l = l0[b].copy()
        _one(R, l, a[b], jc[b], js[b], phase[b], n_periods, n_steps, every, weights, zen[b], jac[b])


def _sample_arrays(
    spec: BatchSpec, periods: int, steps_per_period: int, samples_per_period: int
) -> tuple[int, np.ndarray, np.ndarray]:
    """Checked sampling: ``(steps between samples, zenith array, jacobi array)``, both (B, n)."""
    if steps_per_period <= 0 or samples_per_period <= 0 or steps_per_period % samples_per_period:
        raise ValueError(
            f"steps per period ({steps_per_period}) must be a positive multiple of the samples "
            f"per period ({samples_per_period})"
        )
    n = periods * samples_per_period + 1
    return steps_per_period // samples_per_period, np.empty((spec.size, n)), np.empty((spec.size, n))


def run_batch_numba(
    spec: BatchSpec,
    periods: int,
    steps_per_period: int = 64,
    samples_per_period: int = 1,
    method: str = "suzuki4",
) -> BatchResult:
    """Integrate every scene of ``spec`` for ``periods`` drive periods (numba, cached kernel)."""
    every, zen, jac = _sample_arrays(spec, periods, steps_per_period, samples_per_period)
    _batch(
        np.ascontiguousarray(spec.R0, dtype=float),
        np.ascontiguousarray(spec.l0, dtype=float),
        *(np.ascontiguousarray(v, dtype=float) for v in (spec.inertia_ratio, spec.j_c, spec.j_s, spec.phase)),
        int(periods),
        int(steps_per_period),
        int(every),
        weights_for(method),
        zen,
        jac,
    )
    return BatchResult(zen, jac, samples_per_period)


# --------------------------------------------------------------------------- numpy version


def _torque(R: np.ndarray, jc: np.ndarray, js: np.ndarray, th: np.ndarray) -> np.ndarray:
    u = R[:, :, 2]
    b = np.stack([-jc * np.sin(th), jc * np.cos(th), js], axis=1)
    return np.cross(u, b)


def _jacobi_np(R, l, a, jc, js, th):
    pi = np.einsum("bji,bj->bi", R, l)
    kin = 0.5 * (pi[:, 0] ** 2 + pi[:, 1] ** 2 + pi[:, 2] ** 2 / a)
    pot = -(-jc * np.sin(th) * R[:, 0, 2] + jc * np.cos(th) * R[:, 1, 2] + js * R[:, 2, 2])
    return kin + pot - l[:, 2]


def run_batch_numpy(
    spec: BatchSpec,
    periods: int,
    steps_per_period: int = 64,
    samples_per_period: int = 1,
    method: str = "suzuki4",
) -> BatchResult:
    """The same scheme as :func:`run_batch_numba`, vectorised over the batch with numpy."""
    every, zen, jac = _sample_arrays(spec, periods, steps_per_period, samples_per_period)
    R = np.array(spec.R0, dtype=float)
    l = np.array(spec.l0, dtype=float)
    a, jc, js, ph = (np.asarray(v, dtype=float) for v in (spec.inertia_ratio, spec.j_c, spec.j_s, spec.phase))
    inv_a1 = 1.0 / a - 1.0
    weights = weights_for(method)
    zen[:, 0] = np.arccos(np.clip(R[:, 2, 2], -1.0, 1.0))
    jac[:, 0] = _jacobi_np(R, l, a, jc, js, ph)
    h = 2.0 * math.pi / steps_per_period
    k = 0
    s = 0.0
    for period in range(periods):
        for step in range(steps_per_period):
            for w in weights:
                hw = w * h
                l += 0.5 * hw * _torque(R, jc, js, s + ph)
                c = hw * np.einsum("bi,bi->b", R[:, :, 2], l) * inv_a1
                cc, sc = np.cos(c)[:, None], np.sin(c)[:, None]
                p, q = R[:, :, 0].copy(), R[:, :, 1].copy()
                R[:, :, 0] = cc * p + sc * q
                R[:, :, 1] = -sc * p + cc * q
                ln = np.sqrt(np.einsum("bi,bi->b", l, l))
                axis = l / np.where(ln > 0, ln, 1.0)[:, None]
                ang = hw * ln
                co, si = np.cos(ang)[:, None, None], np.sin(ang)[:, None, None]
                kx = np.zeros((spec.size, 3, 3))
                kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
                kx[:, 1, 0], kx[:, 2, 0], kx[:, 2, 1] = axis[:, 2], -axis[:, 1], axis[:, 0]
                rot = np.eye(3) * co + si * kx + (1.0 - co) * np.einsum("bi,bj->bij", axis, axis)
                R = np.einsum("bij,bjk->bik", rot, R)
                s += hw
                l += 0.5 * hw * _torque(R, jc, js, s + ph)
            s = 2.0 * math.pi * (period + (step + 1.0) / steps_per_period)
            if (step + 1) % every == 0:
                k += 1
                zen[:, k] = np.arccos(np.clip(R[:, 2, 2], -1.0, 1.0))
                jac[:, k] = _jacobi_np(R, l, a, jc, js, s + ph)
    return BatchResult(zen, jac, samples_per_period)


# --------------------------------------------------------------------------- timing


def compile_numba_kernel() -> float:
    """Load (or compile, first time on this machine) the numba kernel; returns seconds taken."""
    start = time.perf_counter()
    spec = BatchSpec(
        np.array([1e-2]), np.array([1e-2]), np.array([1.0]), np.zeros(1), np.eye(3)[None], np.zeros((1, 3))
    )
    run_batch_numba(spec, 1, 4, 1)
    return time.perf_counter() - start


def kernel_timings(spec: BatchSpec, periods: int, steps_per_period: int = 64, repeats: int = 2) -> dict:
    """Compile time and best-of-``repeats`` run time of both batch kernels on ``spec``.

    Returns ns per trajectory-step for each, their ratio and the largest difference between
    their results (they run the same arithmetic in a different order).
    """
    compile_s = compile_numba_kernel()
    steps = spec.size * periods * steps_per_period
    out: dict = {
        "compile_s": compile_s,
        "batch": spec.size,
        "periods": periods,
        "steps_per_period": steps_per_period,
    }
    results = {}
    for name, fn in (("numba", run_batch_numba), ("numpy", run_batch_numpy)):
        best = math.inf
        for _ in range(repeats):
            start = time.perf_counter()
            results[name] = fn(spec, periods, steps_per_period)
            best = min(best, time.perf_counter() - start)
        out[f"{name}_s"] = best
        out[f"{name}_ns_per_trajectory_step"] = 1e9 * best / steps
    out["numpy_over_numba"] = out["numpy_s"] / out["numba_s"]
    diff = np.abs(results["numba"].zenith - results["numpy"].zenith)
    out["max_zenith_difference_rad"] = float(np.max(diff))
    out["faster"] = "numba" if out["numba_s"] <= out["numpy_s"] else "numpy"
    return out


# --------------------------------------------------------------------------- from scenes


def spec_from_scenes(scenes: list) -> BatchSpec:
    """Nondimensional :class:`BatchSpec` of one-body scenes in a uniform rotating field.

    Each scene must have a single axisymmetric body (``I_xx = I_yy``, diagonal tensor) with its
    dipole on body z, and a rotating field with ``omega > 0``; otherwise ``ValueError`` says why.
    """
    rows = []
    for scene in scenes:
        fld = scene.field
        if len(scene.bodies) != 1 or scene.rotators or fld is None or fld.kind != "rotating":
            raise ValueError(f"{scene.name}: the fast kernel needs one body in a rotating uniform field")
        if fld.omega_rad_s <= 0:
            raise ValueError(f"{scene.name}: the fast kernel needs a positive drive speed")
        body = scene.bodies[0]
        inertia = np.asarray(body.inertia_kg_m2, dtype=float)
        m = np.asarray(body.moment_Am2, dtype=float)
        if (
            np.any(np.abs(inertia - np.diag(np.diag(inertia))) > 0)
            or not math.isclose(inertia[0, 0], inertia[1, 1], rel_tol=1e-12)
            or np.linalg.norm(m[:2]) > 0
            or m[2] == 0
        ):
            raise ValueError(
                f"{scene.name}: the fast kernel needs an axisymmetric body with its dipole on body z"
            )
        i_r, i_a, w = inertia[0, 0], inertia[2, 2], fld.omega_rad_s
        rotation = np.asarray(body.rotation, dtype=float)
        if m[2] < 0:  # use the dipole direction as body z
            rotation = rotation @ np.diag([1.0, -1.0, -1.0])
        lab_inertia = body.rotation @ inertia @ body.rotation.T
        rows.append(
            (
                abs(m[2]) * fld.B_c_T / (i_r * w * w),
                abs(m[2]) * fld.B_s_T / (i_r * w * w),
                i_a / i_r,
                fld.phase_rad,
                rotation,
                lab_inertia @ np.asarray(body.angular_velocity_rad_s, dtype=float) / (i_r * w),
            )
        )
    jc, js, a, ph, R, l0 = zip(*rows, strict=True)
    return BatchSpec(np.array(jc), np.array(js), np.array(a), np.array(ph), np.array(R), np.array(l0))
