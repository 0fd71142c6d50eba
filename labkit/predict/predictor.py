"""Predict a rig before building it: does the floator bind, where, how stiff, how stable, at
which speeds (user story 5). Every number is an :class:`~labkit.predict.estimate.Estimate`
saying how it was obtained, how accurate it is and what it cost.

Physics (point dipoles, floator on the rotator's spin axis, gravity included):

* axial force F(r) from the co-rotating steady state (Eq. 5.84-5.85 split), equilibrium
  F(r_e) + load = 0 with positive stiffness (Eq. 6.19-6.20), the stiffness limit and the
  largest load (below Eq. 6.22);
* cone angle from Eq. 5.35 with the on-axis torques of Eq. 5.28, beside the steady state's;
* stability of the cone: Eq. 5.46 and the growth rate of the linearised co-rotating dynamics
  (:mod:`labkit.model.conical_dynamics`, which the model tests show coincides with Eq. 5.46);
* speed limits (:mod:`labkit.predict.pair`) and the Eq. 6.18 scaling omega ~ m^-1/3 to other
  floator masses, checked by one direct solve for a geometrically similar floator;
* a time-domain check with :mod:`labkit.sim` (:mod:`labkit.predict.verify`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from labkit.model.cone import cone_angles_axisymmetric
from labkit.model.conical_dynamics import RotatingFieldBody, equilibrium, jacobian
from labkit.model.mbs import scaled_speed
from labkit.model.stability import criterion_holds, min_static_torque
from labkit.predict.estimate import CLOSED_FORM, SIMULATION, STEADY_STATE, Estimate, timed
from labkit.predict.magnets import Magnet
from labkit.predict.pair import (
    ForceCurve,
    Pair,
    check_speed_can_bind,
    min_speed,
    scaled_min_speed_guess,
    speed_for_distance,
)
from labkit.predict.verify import VerifyResult, verify

SCHEMA = "labkit.predict/1"
RPM = 60.0 / (2.0 * math.pi)
POINT_DIPOLE_SIZES = 2.0      # closer than this many magnet sizes the point-dipole model is poor
MASS_FACTORS = (0.125, 0.5, 2.0, 8.0)
GROWTH_NOISE = 1e-6            # growth rates below this (units of omega) are numerical zero


@dataclass
class Prediction:
    """The answer: inputs, the estimates by key, warnings, the verdict and the total cost."""

    inputs: dict
    estimates: dict[str, Estimate] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    scaling: list[dict] = field(default_factory=list)
    verification: dict | None = None
    bound: bool = False
    stable: bool = False
    verdict: str = ""
    cost_s: float = 0.0

    def add(self, est: Estimate) -> None:
        self.estimates[est.key] = est

    def value(self, key: str):
        return self.estimates[key].value if key in self.estimates else None

    def to_json(self) -> dict:
        return {
            "schema": SCHEMA, "inputs": self.inputs, "bound": self.bound, "stable": self.stable,
            "verdict": self.verdict, "results": {k: e.to_json() for k, e in self.estimates.items()},
            "scaling": self.scaling, "verification": self.verification, "warnings": self.warnings,
            "cost_s": self.cost_s,
        }


def _growth_rate(pair: Pair, omega: float, r: float, phi: float) -> tuple[float, float]:
    """Largest real eigenvalue (1/s) of the co-rotating linearisation at the cone (Eq. 5.46's
    exact counterpart) with the Jacobian step halved as its accuracy check."""
    tau_c, tau_s = pair.torques(r)
    f = pair.floator
    body = RotatingFieldBody.from_si(tau_c, tau_s, f.inertia_axial_kg_m2, f.inertia_radial_kg_m2, omega)
    y = equilibrium(phi, body.inertia_ratio)
    rates = [float(np.max(np.linalg.eigvals(jacobian(y, body, h)).real)) for h in (1e-6, 5e-7)]
    return rates[1] * omega, abs(rates[0] - rates[1]) * omega


def scaled_floator(floator: Magnet, mass_factor: float) -> Magnet:
    """A geometrically similar floator of ``mass_factor`` times the mass (Eq. 6.14-6.16):
    sizes x a, mass and moment x a^3, inertia x a^5 with a = mass_factor^(1/3)."""
    a = mass_factor ** (1.0 / 3.0)
    return replace(
        floator, sizes_m=tuple(s * a for s in floator.sizes_m), mass_kg=floator.mass_kg * a**3,
        moment_a_m2=floator.moment_a_m2 * a**3, inertia_axial_kg_m2=floator.inertia_axial_kg_m2 * a**5,
        inertia_radial_kg_m2=floator.inertia_radial_kg_m2 * a**5,
        axial_half_extent_m=floator.axial_half_extent_m * a, size_m=floator.size_m * a,
    )


def predict(pair: Pair, omega: float, run_verify: bool = True, verify_cycles: int = 2000,
            speed_limits: bool = True, scaling: bool = True, xtol: float = 1e-9,
            on_stage: Callable[[str], None] | None = None) -> Prediction:
    """Everything the ``labkit predict`` table shows, for ``pair`` at ``omega`` (rad/s).
    ``on_stage(name)`` is called as each stage starts (``labkit predict`` prints progress lines).

    Raises :class:`labkit.predict.pair.NoSmallConeError` at once when the speed is far too low
    for any bound state (:func:`labkit.predict.pair.check_speed_can_bind`)."""
    check_speed_can_bind(pair, omega, RPM)
    pred = Prediction(inputs={
        "rotator": pair.rotator.to_json(), "floator": pair.floator.to_json(),
        "speed_rpm": omega * RPM, "tilt_deg": math.degrees(pair.gamma), "placement": pair.placement,
        "gravity_m_s2": pair.gravity, "contact_distance_mm": pair.contact_distance * 1e3,
    })
    curve = ForceCurve(pair, omega)
    bs, cost = timed(lambda: curve.bound_state(xtol))
    pred.cost_s += cost
    pred.bound = bs.bound
    solve_note = f"{curve.evaluations} steady states"
    pred.add(Estimate("bound", "bound state exists (point dipoles)", bs.bound, "", STEADY_STATE,
                      "6.19", cost_s=cost, note=bs.reason or solve_note))
    pred.add(Estimate("max_load_N", "largest load carried (stiffness limit)", bs.max_load, "N",
                      STEADY_STATE, "6.20, below 6.22", accuracy=None, cost_s=0.0,
                      note=f"at r = {bs.r_limit * 1e3:.3f} mm; weight {abs(pair.load):.4g} N"))
    if bs.bound:
        _bound_state_numbers(pred, pair, omega, curve, bs)
    stage = on_stage or (lambda name: None)
    if speed_limits:
        stage("bound state done; searching the speed limits")
        _speed_limits(pred, pair, omega, curve, bs)
    if scaling and "min_speed_rpm" in pred.estimates:
        stage("scaling the minimum speed to similar floators")
        _scaling(pred, pair, omega)
    if bs.bound and run_verify:
        stage(f"simulating {verify_cycles} cycles")
        state = curve.state(bs.r_eq)
        ver, cost = timed(lambda: verify(pair, omega, state, cycles=verify_cycles))
        pred.cost_s += cost
        _verification(pred, pair, bs.r_eq, ver, cost)
    _verdict(pred, run_verify)
    return pred


def _bound_state_numbers(pred: Prediction, pair: Pair, omega: float, curve: ForceCurve, bs) -> None:
    r = bs.r_eq
    pred.add(Estimate("r_eq_mm", "equilibrium distance (centre to centre)", r * 1e3, "mm", STEADY_STATE,
                      "6.19", accuracy=bs.r_eq_error * 1e3, accuracy_how="tolerance halving",
                      note="on the stable branch, S > 0"))
    pred.add(Estimate("axial_stiffness_N_m", "axial stiffness", bs.stiffness, "N/m", STEADY_STATE,
                      "6.20", accuracy=bs.stiffness_error, accuracy_how="step halving (Richardson)",
                      note="numeric derivative of the cycle-averaged force"))
    state, cost = timed(lambda: curve.state(r))
    pred.add(Estimate("pfr_force_N", "PFR (repulsion of the cyclic moment)", state.force_cyclic_z, "N",
                      STEADY_STATE, "5.84-5.85", cost_s=cost, note=f"solver residual {state.residual:.1g}"))
    pred.add(Estimate("attraction_N", "attraction of the static moment", -state.force_static_z, "N",
                      STEADY_STATE, "5.84-5.85"))
    pred.add(Estimate("lateral_circle_mm", "lateral circle radius beta", state.beta * 1e3, "mm",
                      STEADY_STATE, "Sec. 5.2, Fig. 5.13"))
    f = pair.floator
    tau_c, tau_s = pair.torques(r)
    (phi_cf, cost) = timed(lambda: float(cone_angles_axisymmetric(
        tau_c=tau_c, tau_s=tau_s, i_axial=f.inertia_axial_kg_m2, i_radial=f.inertia_radial_kg_m2,
        omega=omega)))
    pred.add(Estimate("cone_angle_deg", "cone angle", math.degrees(phi_cf), "deg", CLOSED_FORM,
                      "5.35 (5.24) with 5.28", accuracy=abs(math.degrees(phi_cf - state.phi)),
                      accuracy_how="vs the steady state with its lateral circle", cost_s=cost))
    pred.add(Estimate("cone_angle_steady_deg", "cone angle (with lateral circle)", math.degrees(state.phi),
                      "deg", STEADY_STATE, "5.62"))
    need = float(min_static_torque(tau_c, f.inertia_radial_kg_m2, omega))
    holds = bool(criterion_holds(tau_c, tau_s, f.inertia_radial_kg_m2, omega))
    pred.add(Estimate("eq5_46_ratio", "static torque over the Eq. 5.46 minimum", tau_s / need if need > 0
                      else math.inf, "", CLOSED_FORM, "5.46",
                      note=f"tau_S/tau_C = {tau_s / tau_c:.4g}, minimum {need / tau_c:.4g}; "
                           + ("cone stable" if holds else "cone UNSTABLE")))
    (rate, err), cost = timed(lambda: _growth_rate(pair, omega, r, phi_cf))
    pred.add(Estimate("growth_rate_1_s", "cone growth rate (linear analysis)", rate, "1/s",
                      "linear analysis", "5.46 (co-rotating frame)", accuracy=err,
                      accuracy_how="Jacobian step halving", cost_s=cost))
    size = max(pair.rotator.size_m, pair.floator.size_m)
    if r < POINT_DIPOLE_SIZES * size:
        pred.warnings.append(
            f"r_eq = {r * 1e3:.2f} mm is within {POINT_DIPOLE_SIZES:g} magnet sizes ({size * 1e3:g} mm): "
            "the point-dipole model is poor here; treat distance and stiffness as estimates "
            "(the paper's FEM-coupled values differ by a few % at ~2.4 sizes, more when closer)")


def _speed_limits(pred: Prediction, pair: Pair, omega: float, curve: ForceCurve, bs) -> None:
    rtol = 1e-4
    w_max, cost = timed(lambda: speed_for_distance(pair, pair.contact_distance, omega, rtol=rtol))
    pred.cost_s += cost
    pred.add(Estimate("max_speed_rpm", "maximum speed (equilibrium reaches contact)", w_max * RPM, "rpm",
                      STEADY_STATE, "6.19 at r = contact", accuracy=rtol * w_max * RPM,
                      accuracy_how="root bracket", cost_s=cost,
                      note=f"contact at {pair.contact_distance * 1e3:.2f} mm; real rigs often lose the state "
                           "earlier (resonances, Sec. 6.0.5)"))
    if not math.isfinite(curve.stiffness_limit(1e-7)[1]):
        return
    if pair.load <= 0:
        pred.add(Estimate("min_speed_rpm", "minimum speed (weight = largest attraction)", math.nan, "rpm",
                          STEADY_STATE, "6.19, below 6.22",
                          note="not searched: above the rotator the weight pushes the floator inwards and "
                               "the PFR carries it at any speed; the cone's stability (Eq. 5.46) and the "
                               "point-dipole steady state set the real limit"))
        return
    guess = scaled_min_speed_guess(curve)
    w_min, cost = timed(lambda: min_speed(pair, omega, rtol=rtol, guess=guess))
    pred.cost_s += cost
    note = "largest net attraction = weight"
    if not math.isfinite(w_min):
        note = "none within 1000x below this speed"
    else:
        r_lim, _ = ForceCurve(pair, w_min).stiffness_limit(1e-7)
        tau_c, tau_s = pair.torques(r_lim)
        if not criterion_holds(tau_c, tau_s, pair.floator.inertia_radial_kg_m2, w_min):
            note += "; the cone is already unstable there (Eq. 5.46): the real minimum is higher"
    pred.add(Estimate("min_speed_rpm", "minimum speed (weight = largest attraction)", w_min * RPM, "rpm",
                      STEADY_STATE, "6.19, below 6.22", accuracy=rtol * w_min * RPM,
                      accuracy_how="root bracket", cost_s=cost, note=note))
    if math.isfinite(w_min) and math.isfinite(w_max):
        if not w_min <= omega <= w_max:
            pred.warnings.append(
                f"{omega * RPM:.0f} rpm is outside the bound-state range "
                f"{w_min * RPM:.0f}-{w_max * RPM:.0f} rpm")


def _scaling(pred: Prediction, pair: Pair, omega: float) -> None:
    """Eq. 6.18 (omega ~ m^-1/3) to other floator masses, beside the local exponent from a
    direct solve for a geometrically similar floator of twice the mass."""
    w_min = pred.estimates["min_speed_rpm"].value / RPM
    if not math.isfinite(w_min):
        return
    mass = pair.floator.mass_kg
    twice = replace(pair, floator=scaled_floator(pair.floator, 2.0))
    w_twice, cost = timed(lambda: min_speed(twice, w_min, rtol=1e-4))
    pred.cost_s += cost
    exponent = math.log(w_twice / w_min) / math.log(2.0) if math.isfinite(w_twice) else math.nan
    for factor in MASS_FACTORS:
        row = {"mass_g": factor * mass * 1e3,
               "eq6_18_min_speed_rpm": float(scaled_speed(w_min, mass, factor * mass)) * RPM}
        if math.isfinite(exponent):
            row["local_power_law_rpm"] = w_min * factor**exponent * RPM
        pred.scaling.append(row)
    pred.add(Estimate("scaling_exponent", "min speed ~ m^x, x from a 2x-mass similar floator", exponent, "",
                      STEADY_STATE, "6.18 (x = -1/3)", accuracy=2e-4 / math.log(2.0),
                      accuracy_how="root brackets", cost_s=cost,
                      note="differs from -1/3 where the floator's lateral circle (beta ~ 1/omega^2) "
                           "adds to the PFR; Eq. 6.18 holds for the cone alone"))


def _verification(pred: Prediction, pair: Pair, r_eq: float, ver: VerifyResult, cost: float) -> None:
    pred.verification = {
        "status": ver.status, "status_detail": ver.status_detail, "cycles": ver.cycles, "bound": ver.bound,
        "axial_distance_mean_mm": ver.distance_mean_m * 1e3,
        "axial_distance_min_mm": ver.distance_min_m * 1e3,
        "axial_distance_max_mm": ver.distance_max_m * 1e3, "invariant": ver.invariant,
        "invariant_drift": ver.invariant_drift, "wall_s": ver.wall_s, "compile_s": ver.compile_s,
    }
    how = f"{ver.cycles} cycles, {ver.invariant} drift {ver.invariant_drift:.2g}"
    pred.add(Estimate("sim_bound", "time-domain check stays bound", ver.bound, "", SIMULATION,
                      cost_s=cost, note=f"status {ver.status}; {how}"
                      + (f"; {ver.status_detail}" if ver.status_detail else "")))
    if ver.status != "ok":
        return
    pred.add(Estimate("sim_r_mean_mm", "mean axial distance in the simulation", ver.distance_mean_m * 1e3,
                      "mm", SIMULATION, accuracy=abs(ver.distance_mean_m - r_eq) * 1e3,
                      accuracy_how="difference to the steady-state r_eq", note=how))
    m = pair.floator.mass_kg
    if math.isfinite(ver.axial.stiffness):
        pred.add(Estimate("axial_stiffness_sim_N_m", "axial stiffness (oscillation)", ver.axial.stiffness,
                          "N/m", SIMULATION, accuracy=ver.axial.error, accuracy_how="halving the record",
                          note=f"m w^2, w = {ver.axial.frequencies[0]:.4g} rad/s; dynamic, differs from the "
                               "quasi-static derivative by the cone's response"))
    if math.isfinite(ver.lateral.stiffness):
        wp, wn = ver.lateral.frequencies
        pred.add(Estimate("lateral_stiffness_N_m", "lateral stiffness (whirl)", ver.lateral.stiffness, "N/m",
                          SIMULATION, accuracy=ver.lateral.error, accuracy_how="halving the record",
                          note=f"m w+ w-, whirl {wp:.4g} / {wn:.4g} rad/s (mass {m * 1e3:.3g} g)"))


def _verdict(pred: Prediction, ran_verify: bool) -> None:
    if not pred.bound:
        pred.stable = False
        pred.verdict = "no bound state: " + pred.estimates["bound"].note
        return
    rate = pred.value("growth_rate_1_s") or 0.0
    omega = pred.inputs["speed_rpm"] / RPM
    cone_ok = rate <= GROWTH_NOISE * omega
    lateral = pred.value("lateral_stiffness_N_m")
    sim_ok = pred.value("sim_bound") if ran_verify else None
    problems = []
    if not cone_ok:
        problems.append(f"the cone grows at {rate:.3g}/s")
    if lateral is not None and lateral <= 0:
        problems.append("laterally unstable")
    if sim_ok is False:
        problems.append("the time-domain check lost it")
    pred.stable = not problems
    if problems:
        pred.verdict = "bound but unstable: " + "; ".join(problems)
    else:
        skipped = "" if ran_verify else " (linear analysis; time-domain check skipped)"
        pred.verdict = "bound and stable" + skipped
