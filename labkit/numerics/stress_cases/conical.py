"""Stress cases on one conical body: exact motion, units, singular and stiff torques, frequency
sweep, damping (S1-S4, S10, S11 of docs/reference/bench-sim.md)."""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import cumulative_simpson, simpson

from labkit.numerics import kernels, metrics
from labkit.numerics.stress_cases.common import (
    I_S1,
    OMEGA_S1,
    TAU_C_S1,
    TAU_S_S1,
    Verdict,
    conical_scene,
    final_phase_error,
    horizon,
    s1_like,
    simulate_case,
    stroboscopic_drift,
)
from labkit.sim.equilibrium import cone_angle_isotropic
from labkit.sim.result import SimResult


def s1(level: str) -> Verdict:
    cycles = 500 if level == "smoke" else 10_000
    base = simulate_case(s1_like(I_S1, OMEGA_S1, name="S1"), cycles, samples_per_period=1)
    # exact mirror 2 I w^2 - tau_S = 8.0001e-3 (the paper's rounded 8e-3 moves phi by 2.4e-5 rad)
    mirror_tau_s = 2.0 * I_S1 * OMEGA_S1**2 - TAU_S_S1
    mirror = simulate_case(s1_like(I_S1, OMEGA_S1, tau_s=mirror_tau_s, name="S1-mirror"), cycles,
                           samples_per_period=1)
    err = final_phase_error(base)
    err_m = final_phase_error(mirror)
    direction_max = max(stroboscopic_drift(base), stroboscopic_drift(mirror))
    rz = np.diag([-1.0, -1.0, 1.0])  # rotation by pi about z
    phase = float(np.max(np.abs(mirror.dipole_directions() - base.dipole_directions() @ rz.T)))
    n = base.setting["steps_per_period"]
    measured = {
        "psi_error": err,
        "psi_error_mirror": err_m,
        "direction_error_max_over_run": direction_max,
        "mirror_minus_rotated_by_pi": phase,
        "steps_per_period": n,
        "wall_s_1e4_cycles": base.wall_s,
        "invariant_drift": base.invariant_drift,
        "drift_growth": metrics.drift_growth(base.invariant_values),
    }
    detail = (
        "psi error: final azimuth at t = 1e4 T (docs/explanation/numerics-notes.md#exact-conical-motion); "
        "the dipole direction's max "
        "deviation over the run is a bounded offset reached in the first cycles, not a growth"
    )
    if level == "full":
        fine = simulate_case(
            s1_like(I_S1, OMEGA_S1, name="S1-2N"), cycles, samples_per_period=1, steps_per_period=2 * n
        )
        measured["psi_error_2N"] = final_phase_error(fine)
        detail += f"; at N = {2 * n}: psi error {measured['psi_error_2N']:.2g}"
    met = max(err, err_m) <= 1e-6 and phase <= 2.0 * direction_max + 1e-12
    return Verdict(
        "S1",
        "exact conical motion, I = 1e-7, w = 80 pi (Sec. 5.1); mirror tau_S = 2 I w^2 - tau_S",
        "psi error <= 1e-6 after 1e4 cycles; mirror = S1 turned by pi about z (within both runs' errors)",
        met,
        measured,
        cycles,
        base.wall_s + mirror.wall_s,
        detail,
    )


def _nondim_state(res: SimResult, omega: float) -> np.ndarray:
    """Dipole direction and angular velocity / omega (what Eq. 5.7 describes; see metrics)."""
    n = len(res.times_s)
    return np.concatenate([res.dipole_directions(), res.angular_velocities_rad_s.reshape(n, -1) / omega], 1)


def scale_invariance(cycles: int, inertias=(1e-12, 1e-9, 1e-6), omegas=(100.0, 11_000.0)) -> dict:
    """T7: SI runs over a grid of (I, omega) against the nondimensional fast kernel (same
    tau / (I omega^2)); max difference of zenith angle (rad) and of the Jacobi constant (units
    I omega^2) at every sample, and of the SI runs between each other (dimensionless state)."""
    ref_scene = s1_like(I_S1, OMEGA_S1, name="S2-nd")
    spec = kernels.spec_from_scenes([ref_scene])
    nd = kernels.run_batch_numba(spec, cycles, 64, 8)
    base = None
    out = {"vs_nondimensional_zenith": 0.0, "vs_nondimensional_jacobi": 0.0, "between_si_runs": 0.0}
    for i in inertias:
        for w in omegas:
            res = simulate_case(
                s1_like(i, w, name=f"S2-{i:g}-{w:g}"), cycles, steps_per_period=64, samples_per_period=8
            )
            zen = np.arccos(np.clip(res.dipole_directions()[:, 2], -1, 1))
            out["vs_nondimensional_zenith"] = max(
                out["vs_nondimensional_zenith"], float(np.max(np.abs(zen - nd.zenith[0])))
            )
            jac = res.invariant_values / (i * w * w)
            out["vs_nondimensional_jacobi"] = max(
                out["vs_nondimensional_jacobi"], float(np.max(np.abs(jac - nd.jacobi[0])))
            )
            state = _nondim_state(res, w)
            if base is None:
                base = state
            else:
                out["between_si_runs"] = max(out["between_si_runs"], float(np.max(np.abs(state - base))))
    return out


def s2(level: str) -> Verdict:
    cycles = horizon(level, 100, 1000)
    start = time.perf_counter()
    tiny = simulate_case(s1_like(1e-12, 11_000.0, name="S2"), cycles, steps_per_period=64,
                         samples_per_period=8)
    ref = simulate_case(s1_like(I_S1, OMEGA_S1, name="S1"), cycles, steps_per_period=64, samples_per_period=8)
    rel = float(np.max(np.abs(_nondim_state(tiny, 11_000.0) - _nondim_state(ref, OMEGA_S1))))
    grid = scale_invariance(cycles)
    worst = max(rel, *grid.values())
    return Verdict(
        "S2",
        "tiny inertia I = 1e-12 at w = 11 000 rad/s (5 mg at 105k RPM), SI units",
        "matches S1 nondimensionally to <= 1e-10; SI vs nondimensional <= 1e-10 for "
        "I in 1e-12..1e-6, w in 100..11 000 (T7)",
        worst <= 1e-10,
        {"vs_S1": rel, **grid},
        cycles,
        time.perf_counter() - start,
    )


def signed_cone_angle(res: SimResult, omega: float, phase: float = 0.0) -> np.ndarray:
    """Signed cone angle (Eq. 5.24 sign): positive when the dipole's horizontal part points
    against the field's rotating part (PFR anti-phase), at every sample."""
    u = res.dipole_directions()
    th = omega * res.times_s + phase
    along = -np.sin(th) * u[:, 0] + np.cos(th) * u[:, 1]
    return np.arctan2(-along, u[:, 2])


def s3(level: str) -> Verdict:
    cycles = horizon(level, 200, 2000)
    i_w2 = I_S1 * OMEGA_S1**2
    measured: dict = {}
    start = time.perf_counter()
    met = True
    signs = {}
    for label, factor in (("below", 1 - 1e-3), ("at", 1.0), ("above", 1 + 1e-3)):
        tau_s = factor * i_w2
        res = simulate_case(conical_scene(I_S1, OMEGA_S1, TAU_C_S1, tau_s, f"S3-{label}"), cycles)
        phi = signed_cone_angle(res, OMEGA_S1)
        first = phi[: 8 * 10 + 1]  # the first 10 cycles
        expected = cone_angle_isotropic(omega=OMEGA_S1, tau_c=TAU_C_S1, tau_s=tau_s, inertia=I_S1)
        growth = metrics.drift_growth(res.invariant_values)
        measured[f"phi_{label}_first_10_cycles_rad"] = float(np.mean(first))
        measured[f"phi_{label}_eq5_24_rad"] = expected
        measured[f"phi_{label}_first_10_cycles_error"] = float(np.max(np.abs(first - expected)))
        measured[f"cone_kept_{label}"] = bool(np.max(np.abs(phi - expected)) < 1e-3)
        measured[f"invariant_drift_{label}"] = res.invariant_drift
        measured[f"drift_growth_{label}"] = growth
        signs[label] = math.copysign(1.0, float(np.mean(first)))
        met &= res.invariant_drift <= 1e-6 and growth <= 3.0
    measured["sign_flip_reproduced"] = signs["below"] == -signs["above"] and signs["below"] == 1.0
    met &= measured["sign_flip_reproduced"]
    return Verdict(
        "S3",
        "tau_S -> I w^2 (phi -> pi/2, Eq. 5.24 singular) and tau_S > I w^2 (sign flip)",
        "invariant bounded (drift <= 1e-6, growth 1e3 -> all cycles <= 3x); the sign of phi "
        "flips across tau_S = I w^2 as Eq. 5.24 says",
        met,
        measured,
        cycles,
        time.perf_counter() - start,
        "cone_kept_* false means the cone left Eq. 5.24 (physical instability near pi/2, "
        "with the invariant still conserved)",
    )


def s4(level: str) -> Verdict:
    measured: dict = {}
    met = True
    start = time.perf_counter()
    cycles_for = {10: horizon(level, 100, 1000), 100: horizon(level, 10, 100)}
    for ratio, cycles in cycles_for.items():
        tau_s = ratio**2 * I_S1 * OMEGA_S1**2
        res = simulate_case(conical_scene(I_S1, OMEGA_S1, TAU_C_S1, tau_s, f"S4-{ratio}"), cycles)
        err = stroboscopic_drift(res)
        at_1e4 = err * 1e4 / cycles
        measured[f"w0_{ratio}w_steps_per_period"] = res.setting["steps_per_period"]
        measured[f"w0_{ratio}w_psi_error"] = err
        measured[f"w0_{ratio}w_psi_error_at_1e4_cycles"] = at_1e4
        measured[f"w0_{ratio}w_cycles"] = cycles
        met &= at_1e4 <= 2e-6
    return Verdict(
        "S4",
        "internal frequency w0 = sqrt(tau_S / I) = 10 w and 100 w",
        "automatic N keeps the psi error within 2x of S1's target (2e-6 after 1e4 cycles)",
        met,
        measured,
        max(cycles_for.values()),
        time.perf_counter() - start,
        "errors scaled linearly from the horizons listed to 1e4 cycles",
    )


def s10(level: str) -> Verdict:
    cycles = horizon(level, 1000, 3000)
    start = time.perf_counter()
    omegas = (100.0, 1000.0, 11_000.0)
    scenes = {w: s1_like(I_S1, w, name=f"S10-{w:g}") for w in omegas}
    best = {w: math.inf for w in omegas}
    for _ in range(5):  # interleaved rounds: a burst of load on the shared machine hits all speeds
        for w in omegas:
            best[w] = min(best[w], simulate_case(scenes[w], cycles, samples_per_period=1).wall_s)
    per = {f"wall_s_per_1e3_cycles_at_{w:g}": best[w] * 1e3 / cycles for w in omegas}
    ratio = max(per.values()) / min(per.values())
    return Verdict(
        "S10",
        "frequency sweep 100 -> 11 000 rad/s, same geometry (same tau / (I w^2))",
        "wall time per 1e3 cycles independent of w within 20 %",
        ratio <= 1.2,
        {**per, "max_over_min": ratio},
        cycles,
        time.perf_counter() - start,
        "best of 5 interleaved runs each; the machine is shared, so timing noise can still fail this case",
    )


def energy_budget_residual(
    res: SimResult, inertia: float, c_rot: float, omega: float, b_c: float, b_s: float, moment: float
) -> float:
    """max |E(t) - E(0) - int (P_in - P_diss) dt| / max(|E(0)|, int |P_in| dt) over the run
    (isotropic body, Eq. 5.21 field): P_in = -m . dB/dt, P_diss = c_rot |Omega|^2."""
    t = res.times_s
    u = res.dipole_directions()
    w = res.angular_velocities_rad_s[:, 0]
    th = omega * t
    b = np.stack([-b_c * np.sin(th), b_c * np.cos(th), np.full_like(t, b_s)], axis=1)
    db = np.stack([-b_c * omega * np.cos(th), -b_c * omega * np.sin(th), np.zeros_like(t)], axis=1)
    energy = 0.5 * inertia * np.sum(w * w, axis=1) - moment * np.sum(u * b, axis=1)
    power = -moment * np.sum(u * db, axis=1) - c_rot * np.sum(w * w, axis=1)
    work = cumulative_simpson(power, x=t, initial=0.0)
    scale = max(abs(energy[0]), float(simpson(np.abs(power), x=t)))
    return float(np.max(np.abs(energy - energy[0] - work)) / scale)


def s11(level: str) -> Verdict:
    cycles = horizon(level, 10, 40)
    start = time.perf_counter()
    n = 256
    measured: dict = {"steps_per_period": n}
    c_liquid = 0.1 * OMEGA_S1 * I_S1  # damping rate c / I = w / 10: liquid-like
    res = simulate_case(
        conical_scene(I_S1, OMEGA_S1, TAU_C_S1, TAU_S_S1, "S11", damping_rot=c_liquid),
        cycles,
        steps_per_period=n,
        samples_per_period=n,
    )
    residual = energy_budget_residual(res, I_S1, c_liquid, OMEGA_S1, TAU_C_S1, TAU_S_S1, 1.0)
    measured.update(budget_residual=residual, status=res.status, simulator_budget_drift=res.invariant_drift)
    c_stiff = 100.0 * OMEGA_S1 * I_S1  # c / I = 100 w: overdamped, stiff against the step
    stiff = simulate_case(conical_scene(I_S1, OMEGA_S1, TAU_C_S1, TAU_S_S1, "S11-stiff", damping_rot=c_stiff),
                          cycles)
    finite = bool(np.all(np.isfinite(stiff.angular_velocities_rad_s)))
    measured.update(
        stiff_status=stiff.status,
        stiff_finite=finite,
        stiff_steps_per_period=stiff.setting["steps_per_period"],
        stiff_final_cone_angle_rad=float(np.arccos(np.clip(stiff.dipole_directions()[-1, 2], -1, 1))),
    )
    met = residual <= 1e-8 and finite and stiff.status == "ok"
    return Verdict(
        "S11",
        "rotational damping c / I = w / 10 (liquid-like) and c / I = 100 w (stiff)",
        "energy-budget residual <= 1e-8 relative; stiff case runs at the automatic step without "
        "NaN or blow-up",
        met,
        measured,
        cycles,
        time.perf_counter() - start,
        "budget integrated with Simpson's rule on every step; its own error is included",
    )
