"""``simulate``: scene -> compiled system -> integrator -> :class:`SimResult`.

A run never silently returns garbage: non-finite values, blow-up, contact, escape, a failed
reference solver, invariant drift above ``drift_threshold`` or a rotation residual above
``rotation_threshold`` set ``result.status`` (and ``status_detail`` says what and when).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from labkit.sim import equilibrium
from labkit.sim.attitude import ATTITUDES, body_axis
from labkit.sim.compile import CompiledSystem, compile_scene
from labkit.sim.integrators import DEFAULT_INTEGRATOR, get_integrator
from labkit.sim.integrators.kernels import invariants_over_samples
from labkit.sim.integrators.raw_run import RawRun, SimulationError
from labkit.sim.integrators.status import LABELS, MESSAGES, Status
from labkit.sim.result import SimResult
from labkit.sim.rotations import orthonormality_residual, rot_x, rot_z, zenith_angle
from labkit.sim.scene import Scene
from labkit.sim.scene_file import load_scene

#: kernel status code -> ``SimResult.status`` (kept for callers; :mod:`.integrators.status` names them)
RAW_STATUS = {int(code): label for code, label in LABELS.items()}


def simulate(
    scene: Scene | str | Path,
    cycles: float | None = None,
    integrator: str = DEFAULT_INTEGRATOR,
    steps_per_period: int | None = None,
    samples_per_period: int = 8,
    rtol: float = 1e-10,
    drift_threshold: float = 1e-6,
    rotation_threshold: float = 1e-6,
    system: CompiledSystem | None = None,
    decimate: int = 1,
    attitude: str = "axis",
) -> SimResult:
    """Simulate ``cycles`` drive periods of ``scene`` (a :class:`Scene`, a TOML path or a bundled name).

    ``steps_per_period`` applies to splittings (automatic if None), ``rtol`` to scipy references.
    ``decimate`` keeps every ``decimate``-th of the ``samples_per_period`` samples (and the last):
    memory then grows as ``cycles * samples_per_period / decimate`` (long runs, docs/reference/simulator.md).
    ``attitude`` "axis" keeps an axisymmetric body's axis and any other body's rotation matrix;
    "matrix" keeps every body's rotation matrix (:mod:`labkit.sim.attitude`).
    """
    if not (isinstance(decimate, int) and decimate >= 1):
        raise SimulationError(f"decimate must be a whole number >= 1, got {decimate!r}")
    if attitude not in ATTITUDES:
        raise SimulationError(f"attitude must be one of {', '.join(ATTITUDES)}, got {attitude!r}")
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    system = system or compile_scene(scene)
    cycles = float(cycles if cycles is not None else scene.cycles)
    run = get_integrator(integrator)
    start = time.perf_counter()
    raw = run(
        system, cycles, steps_per_period=steps_per_period, samples_per_period=samples_per_period, rtol=rtol,
        decimate=decimate,
    )
    wall = time.perf_counter() - start - raw.extra.get("compile_s", 0.0)
    return assemble(scene, system, raw, cycles, wall, drift_threshold, rotation_threshold, attitude)


def assemble(
    scene: Scene,
    system: CompiledSystem,
    raw: RawRun,
    cycles: float,
    wall: float,
    drift_threshold: float = 1e-6,
    rotation_threshold: float = 1e-6,
    attitude: str = "axis",
) -> SimResult:
    """Turn an integrator's :class:`RawRun` into a :class:`SimResult` (invariants, status, QoIs)."""
    axis_body, keep = _attitudes(scene, attitude)
    if system.reduced is not None:
        parts = _reduced_parts(system, raw, axis_body, keep)
    else:
        parts = _rigid_parts(system, raw, axis_body, keep)
    code = Status(raw.status)
    status = code.label
    detail = MESSAGES[code].format(r_escape=system.r_escape, message=raw.message)
    if code in (Status.NONFINITE, Status.BLOWUP, Status.CONTACT, Status.ESCAPE):
        detail += f" at t = {raw.event_time:.9g} s (cycle {raw.event_time / system.period:.4g})"
    drift = parts["drift"]
    if status == "ok" and drift is not None and not (drift <= drift_threshold):
        status = "invariant_drift"
        detail = f"{system.invariant} drifted by {drift:.3g} (relative) > threshold {drift_threshold:.3g}"
    if status == "ok" and not (parts["rot_res"] <= rotation_threshold):
        status = "rotation_drift"
        detail = f"rotation matrices left SO(3) by {parts['rot_res']:.3g} > {rotation_threshold:.3g}"
    event = float(raw.event_time) if raw.status in (1, 2, 3, 4) and math.isfinite(raw.event_time) else None
    return SimResult(
        scene=scene.name,
        integrator=raw.integrator,
        setting=raw.setting,
        status=status,
        status_detail=detail,
        cycles=cycles,
        period_s=system.period,
        times_s=raw.t,
        body_names=system.body_names,
        positions_m=parts["x"],
        velocities_m_s=parts["v"],
        axes=parts["axes"],
        axis_body=axis_body,
        rotation_matrices=parts["matrices"],
        angular_velocities_rad_s=parts["w"],
        invariant=system.invariant,
        invariant_values=parts["inv"],
        invariant_drift=drift if drift is not None else math.nan,
        rotation_residual=parts["rot_res"],
        qoi=_qoi(scene, system, raw, parts),
        compile=system.summary(),
        wall_s=wall,
        compile_s=raw.extra.get("compile_s", 0.0),
        n_force_evals=raw.n_force,
        event_time_s=event,
        momentum_drift=parts.get("p_drift"),
        angular_momentum_drift=parts.get("j_drift"),
        damping_change=raw.budget if system.invariant.endswith("budget") else None,
        reduced_angle_rad=raw.y,
        reduced_rate_rad_s=raw.yd,
    )


def _rel_drift(values: np.ndarray, scale: float) -> float:
    if len(values) == 0:
        return math.nan
    d = np.abs(values - values[0])
    return float(np.max(d) / scale) if np.all(np.isfinite(values)) else math.inf


def _attitudes(scene: Scene, attitude: str) -> tuple[np.ndarray, list[bool]]:
    """Each body's axis (body frame) and whether its rotation matrix is kept."""
    axis_body, keep = np.zeros((len(scene.bodies), 3)), []
    for b, body in enumerate(scene.bodies):
        axis_body[b], symmetric = body_axis(body.inertia_kg_m2, body.moment_Am2, body.dipole_offset_m)
        keep.append(attitude == "matrix" or not symmetric)
    return axis_body, keep


def _reduced_parts(system: CompiledSystem, raw: RawRun, axis_body: np.ndarray, keep: list[bool]) -> dict:
    rf = system.reduced
    body = system.scene.bodies[0]
    n = len(raw.t)
    axis_rot, axis = (
        (rot_x, np.array([1.0, 0.0, 0.0])) if rf.form == 0 else (rot_z, np.array([0.0, 0.0, 1.0]))
    )
    R = np.array([axis_rot(a - rf.y0) @ body.rotation for a in raw.y]).reshape(n, 3, 3)
    axes = (R @ axis_body[0])[:, None, :]
    matrices = {0: R} if keep[0] else {}
    w = (raw.yd[:, None] * axis)[:, None, :]
    x = np.repeat(np.asarray(body.position_m, float)[None, None, :], n, axis=0)
    v = np.zeros_like(x)
    if rf.form == 1:
        th = rf.omega * raw.t + rf.phase
        inv = rf.inertia * (0.5 * raw.yd**2 + rf.jc * np.cos(raw.y - th) - rf.omega * raw.yd)
        scale = rf.inertia * (0.5 * rf.yd0**2 + abs(rf.jc) + abs(rf.omega * rf.yd0)) or 1.0
        drift = _rel_drift(inv, scale)
    else:
        inv, drift = np.full(n, math.nan), None
    return {"x": x, "v": v, "axes": axes, "matrices": matrices, "w": w, "inv": inv, "drift": drift,
            "rot_res": 0.0}


def _free_flight(system: CompiledSystem, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form CM motion when translation is not integrated (gravity and linear damping)."""
    scene = system.scene
    g = np.zeros(3) if scene.gravity_m_s2 is None else np.asarray(scene.gravity_m_s2, float)
    xs, vs = [], []
    dt = (t - t[0])[:, None]
    for b in scene.bodies:
        x0, v0 = np.asarray(b.position_m, float), np.asarray(b.velocity_m_s, float)
        if b.pinned:
            xs.append(np.repeat(x0[None], len(t), 0))
            vs.append(np.zeros((len(t), 3)))
            continue
        k = b.damping_N_s_m / b.mass_kg
        if k > 0:
            e = np.exp(-k * dt)
            xs.append(x0 + (v0 - g / k) * (1 - e) / k + g / k * dt)
            vs.append((v0 - g / k) * e + g / k)
        else:
            xs.append(x0 + v0 * dt + 0.5 * g * dt**2)
            vs.append(v0 + g * dt)
    return np.stack(xs, 1), np.stack(vs, 1)


def _rigid_parts(system: CompiledSystem, raw: RawRun, axis_body: np.ndarray, keep: list[bool]) -> dict:
    bf = system.bf
    Rp = raw.R  # principal frame -> lab; body -> lab is Rp V^T (V: system.frames)
    axes = np.empty(Rp.shape[:2] + (3,))
    matrices = {}
    for b, frame in enumerate(system.frames):
        axes[:, b] = Rp[:, b] @ (frame.T @ axis_body[b])
        if keep[b]:
            matrices[b] = Rp[:, b] @ frame.T
    pi = np.einsum("nbji,nbj->nbi", Rp, raw.L)
    w = np.einsum("nbij,nbj->nbi", Rp, pi / bf[None, :, 1:4])
    if system.bi[:, 0].any():
        x, v = raw.x, raw.v
    else:
        x, v = _free_flight(system, raw.t)
    out = {"x": x, "v": v, "axes": axes, "matrices": matrices, "w": w,
           "rot_res": orthonormality_residual(Rp) if len(Rp) else 0.0}
    if not len(raw.t):
        out.update(inv=np.zeros(0), drift=None)
        return out
    terms = invariants_over_samples(
        raw.t,
        np.ascontiguousarray(raw.x),
        np.ascontiguousarray(raw.v),
        np.ascontiguousarray(Rp),
        np.ascontiguousarray(raw.L),
        bf,
        system.bi,
        system.src,
        system.fld,
        system.flags,
        system.g,
        system.axis,
    )
    kin, pot, jz = terms[:, 0], terms[:, 1], terms[:, 2]
    budget = raw.budget if raw.budget is not None and system.invariant.endswith("budget") else 0.0
    if system.invariant.startswith("jacobi"):
        inv = kin + pot - system.wz * jz - budget
        scale = abs(kin[0]) + abs(pot[0]) + abs(system.wz * jz[0])
        out.update(inv=inv, drift=_rel_drift(inv, scale or 1.0))
    elif system.invariant.startswith("energy"):
        inv = kin + pot - budget
        out.update(inv=inv, drift=_rel_drift(inv, (abs(kin[0]) + abs(pot[0])) or 1.0))
        if system.invariant == "energy+momenta":
            p, j = terms[:, 3:6], terms[:, 6:9]
            m = bf[:, 0]
            p_scale = (
                float(np.sum(m * np.max(np.linalg.norm(raw.v, axis=2), axis=0)))
                or float(np.sum(m)) * system.length_scale * system.omega
            )
            j_scale = float(np.sum(np.linalg.norm(raw.L[0], axis=1))) + float(np.linalg.norm(j[0]))
            out["p_drift"] = float(np.max(np.linalg.norm(p - p[0], axis=1)) / (p_scale or 1.0))
            out["j_drift"] = float(np.max(np.linalg.norm(j - j[0], axis=1)) / (j_scale or 1.0))
            out["drift"] = max(out["drift"], out["p_drift"], out["j_drift"])
    else:
        out.update(inv=np.full(len(raw.t), math.nan), drift=None)
    return out


def _qoi(scene: Scene, system: CompiledSystem, raw: RawRun, parts: dict) -> dict:
    qoi: dict = {"bodies": {}}
    t = raw.t
    duration = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    for b, body in enumerate(scene.bodies):
        entry: dict = {}
        m = np.asarray(body.moment_Am2, float)
        if np.linalg.norm(m) > 0 and len(t):
            zen = zenith_angle(parts["axes"][:, b])  # the axis of a body with a dipole is its direction
            entry["cone_angle_rad"] = {
                "mean": float(zen.mean()),
                "min": float(zen.min()),
                "max": float(zen.max()),
            }
            eq = _cone_angle_closed_form(scene, body)
            if eq is not None:
                entry["cone_angle_closed_form_rad"] = eq
        if raw.impulse is not None and duration > 0 and system.flags is not None and system.flags[5]:
            entry["mean_force_N"] = (raw.impulse[b] / duration).tolist()
        elif system.bi is not None and system.bi[b, 0] and duration > 0 and len(t) > 1:
            g = system.g
            entry["mean_force_N"] = (
                body.mass_kg * ((parts["v"][-1, b] - parts["v"][0, b]) / duration - g)
            ).tolist()
        qoi["bodies"][body.name] = entry
    if system.reduced is not None and len(t):
        qoi["reduced"] = {
            "equation": system.reduced.equation,
            "angle_mean_rad": float(np.mean(raw.y)),
            "angle_amplitude_rad": float(0.5 * (np.max(raw.y) - np.min(raw.y))),
        }
    pair = _main_pair(scene)
    if pair is not None and len(t):
        a, other = pair
        pa = parts["x"][:, a]
        pb = (
            parts["x"][:, other]
            if isinstance(other, int)
            else np.asarray(scene.rotators[0].axis_point_m)[None]
        )
        d = np.linalg.norm(pa - pb, axis=-1)
        qoi["distance_m"] = {
            "mean": float(d.mean()),
            "min": float(d.min()),
            "max": float(d.max()),
            "final": float(d[-1]),
        }
    return qoi


def _main_pair(scene: Scene):
    if scene.rotators:
        return 0, "rotator"
    if len(scene.bodies) >= 2:
        return 1, 0
    return None


def _cone_angle_closed_form(scene: Scene, body) -> float | None:
    """Eq. 5.64 with the body's spin k (Eq. 5.35 / 5.24 for k = -1) at its initial position."""
    inertia = np.asarray(body.inertia_kg_m2, float)
    if not (np.allclose(inertia, np.diag(np.diag(inertia))) and math.isclose(inertia[0, 0], inertia[1, 1])):
        return None
    spin = float(np.linalg.norm(body.angular_velocity_rad_s))
    if (
        scene.field is None
        and not scene.rotators
        and any(
            o is not body and float(np.linalg.norm(o.angular_velocity_rad_s)) < spin for o in scene.bodies
        )
    ):
        return None  # the faster-spinning body is the rotator, not a floator on a cone
    try:
        omega, _, tau_c, tau_s = equilibrium._drive(body, scene)
        return equilibrium.cone_angle_axisymmetric(
            omega=omega, tau_c=tau_c, tau_s=tau_s, i_radial=inertia[0, 0], i_axial=inertia[2, 2],
            spin_k=body.spin_k,
        )
    except ValueError:
        return None
