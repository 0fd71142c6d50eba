"""Integrators against closed forms, each other and the conservation laws.

* Sec. 5.1 conical motion: the exact solution is Eq. 5.7 with phi from Eq. 5.24.
* Observed order of the compositions (4 for Suzuki/Yoshida-4, 2 for Strang, 6 for Yoshida-6).
* Splitting vs scipy DOP853 (independent method) on a scene with translation and forces.
* Jacobi constant (driven) and E, P, J (two free bodies).
* Scale invariance (NUMERICS S2): a 1e-12 kg m^2 body at 11 000 rad/s with the same
  tau / (I omega^2) is the same ODE as S1.
* Reduced forms: Eq. 5.56 reduced equals the full rigid-body run; Table 5.4 case 2 Fourier series.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from labkit.sim import compile_scene, load_scene, simulate
from labkit.sim.rotations import euler_zxz

from .conftest import bundled_dict, make

W = 80 * math.pi
PHI = math.atan(1e-3 / (1e-7 * W**2 - 4.633e-3))  # Eq. 5.24


def _conical_error(result) -> tuple[float, float]:
    exact = np.array([euler_zxz(W * t, PHI, -W * t) for t in result.times_s])  # Eq. 5.7
    dipole = result.rotations[:, 0, :, 2]
    return float(np.abs(result.rotations[:, 0] - exact).max()), float(np.abs(dipole - exact[:, :, 2]).max())


def test_conical_motion_follows_eq_5_7_and_converges_at_order_4(conical):
    errors = [_conical_error(simulate(conical, cycles=200, steps_per_period=n, attitude="matrix"))
              for n in (32, 64)]
    (r32, psi32), (r64, psi64) = errors
    assert math.log2(r32 / r64) == pytest.approx(4.0, abs=0.3)
    assert psi64 < 5e-6  # dipole direction after 200 cycles at the default N = 64
    result = simulate(conical, cycles=200)
    assert result.status == "ok"
    assert result.qoi["bodies"]["floator"]["cone_angle_rad"]["mean"] == pytest.approx(PHI, abs=2e-6)
    assert result.invariant == "jacobi" and result.invariant_drift < 1e-12
    assert result.rotation_residual < 1e-12


@pytest.mark.parametrize(
    "name, order, steps",
    [
        ("splitting4", 4, (16, 32, 64)),
        ("yoshida4", 4, (32, 64, 128)),
        ("strang", 2, (128, 256, 512)),
        ("yoshida6", 6, (16, 32, 64)),
    ],
)
def test_observed_order(conical, name, order, steps):
    scene = copy.deepcopy(conical)  # off the relative equilibrium: a generic orbit
    scene.bodies[0].angular_velocity_rad_s = scene.bodies[0].angular_velocity_rad_s + np.array(
        [5.0, -3.0, 2.0]
    )
    def last_attitude(n: int, integrator: str) -> np.ndarray:  # the full matrix, spin phase included
        run = simulate(scene, cycles=10, steps_per_period=n, integrator=integrator, attitude="matrix")
        return run.rotation(0)[-1]

    ref = last_attitude(2048, "yoshida6")
    errs = [np.abs(last_attitude(n, name) - ref).max() for n in steps]
    assert math.log2(errs[1] / errs[2]) == pytest.approx(order, abs=0.3)


def test_splitting_agrees_with_dop853_on_a_moving_floator():
    d = bundled_dict("fig5_13")
    d["body"][0]["pinned"] = False
    scene = make(d)
    a = simulate(scene, cycles=5, steps_per_period=256, attitude="matrix")
    b = simulate(scene, cycles=5, integrator="dop853", rtol=1e-12, attitude="matrix")
    assert a.status == b.status == "ok"
    np.testing.assert_allclose(a.times_s, b.times_s, rtol=0, atol=1e-15)
    assert np.abs(a.positions_m - b.positions_m).max() < 1e-10  # metres, over mm-scale motion
    assert np.abs(a.rotations - b.rotations).max() < 1e-7
    assert a.invariant_drift < 1e-9
    assert a.n_force_evals > 0 and b.n_force_evals > 0


def test_two_free_bodies_conserve_energy_momentum_and_angular_momentum():
    result = simulate("mbs_fig6_1", cycles=100)
    assert result.status == "ok", result.status_detail
    assert result.invariant == "energy+momenta"
    assert result.invariant_drift < 1e-8
    assert result.momentum_drift < 1e-12 and result.angular_momentum_drift < 1e-12
    d = result.qoi["distance_m"]
    assert 0.020 < d["min"] < d["max"] < 0.030  # still bound near the paper's 24.5 mm


def test_tiny_fast_body_is_the_same_ode_as_s1(conical):
    """S2: I = 1e-12 kg m^2 at 11 000 rad/s with S1's tau / (I w^2) gives S1's motion in t * w."""
    small = copy.deepcopy(conical)
    scale = 1e-12 * 11000.0**2 / (1e-7 * W**2)
    small.field.omega_rad_s = 11000.0
    small.field.B_c_T *= scale
    small.field.B_s_T *= scale
    body = small.bodies[0]
    body.inertia_kg_m2 = np.eye(3) * 1e-12
    body.angular_velocity_rad_s = body.angular_velocity_rad_s * (11000.0 / W)
    a = simulate(conical, cycles=50, attitude="matrix")
    b = simulate(small, cycles=50, attitude="matrix")
    np.testing.assert_allclose(b.times_s * 11000.0, a.times_s * W, rtol=1e-13)
    assert np.abs(a.rotations - b.rotations).max() < 1e-10
    # DOP853 with per-component atol (L ~ 1e-8 here) makes the same error at both scales
    errs = []
    for sc, w in ((small, 11000.0), (conical, W)):
        c = simulate(sc, cycles=20, integrator="dop853", rtol=1e-10, attitude="matrix")
        t_end = c.times_s[-1]
        errs.append(np.abs(c.rotations[-1, 0] - euler_zxz(w * t_end, PHI, -w * t_end)).max())  # Eq. 5.7
    assert errs[0] < 1e-5
    assert errs[0] == pytest.approx(errs[1], rel=0.05)


def test_planar_reduction_equals_the_full_rigid_body_run():
    scene = load_scene("planar_5_56")
    reduced = simulate(scene, cycles=20)
    full = simulate(scene, cycles=20, system=compile_scene(scene, reduce=False))
    assert full.compile["kind"] == "rigid" and reduced.compile["kind"] == "planar"
    psi = full.dipole_directions(0, [0.0, 0.0, 1.0])  # body z
    theta = np.unwrap(np.arctan2(psi[:, 0], -psi[:, 1]))  # Eq. 5.52
    assert np.abs(theta - reduced.reduced_angle_rad).max() < 1e-10
    assert reduced.invariant == "jacobi" and reduced.invariant_drift < 1e-6


def test_table_5_4_case_2_fourier_series():
    """theta = 0.2748 sin wt - 9.55e-3 sin 2wt + 4.3e-4 sin 3wt (Table 5.4, row 2). The paper's
    coefficients have 3-4 digits and omit the b_i and higher terms (~1e-4), hence 3e-4."""
    result = simulate("planar_5_56", cycles=1, samples_per_period=64)
    t = result.times_s
    w = 188.5
    series = 0.2748 * np.sin(w * t) - 9.55e-3 * np.sin(2 * w * t) + 4.3e-4 * np.sin(3 * w * t)
    assert np.abs(result.reduced_angle_rad - series).max() < 3e-4


def test_reduced_eq_5_484_agrees_with_references():
    scene = load_scene("pendulum_5_484")
    a = simulate(scene, cycles=20, steps_per_period=256)
    b = simulate(scene, cycles=20, integrator="dop853", rtol=1e-12)
    assert a.compile["equation"] == "Eq. 5.484"
    assert np.abs(a.reduced_angle_rad - b.reduced_angle_rad).max() < 1e-8
    c = simulate(scene, cycles=2, integrator="lsoda", rtol=1e-10)
    assert c.status == "ok"
    assert np.abs(c.reduced_angle_rad - b.reduced_angle_rad[: len(c.times_s)]).max() < 1e-5


def test_radau_reference_runs(conical):
    result = simulate("planar_5_56", cycles=1, integrator="radau", rtol=1e-8)
    assert result.status == "ok" and result.integrator == "radau"


def test_invariant_has_no_secular_growth():
    """Bounded error (NUMERICS T1): the max drift over 1000 cycles stays within 3x that over 100."""
    scene = load_scene("mbs_fig6_1")
    short = simulate(scene, cycles=100, samples_per_period=1)
    long = simulate(scene, cycles=1000, samples_per_period=1)
    assert long.status == "ok"
    assert long.invariant_drift <= 3 * short.invariant_drift
    assert long.angular_momentum_drift < 1e-12


def test_spinning_body_keeps_the_cone_of_eq_5_68():
    """Fig. 5.11(a): I = 8.1e-8, omega = 80 pi, tau_C = 1e-3, tau_S = 0, spin q = -0.5 (k = -1.5).
    Eq. 5.68 gives phi = 0.1296 rad (the caption: 0.12962) and Eq. 5.62 v_y = 48.71 rad/s (the
    caption: 48.71); the cone is kept without a static field."""
    d = bundled_dict("conical_5_1")
    d["field"]["tau_s_Nm"] = 0.0
    d["body"][0]["inertia_kg_m2"] = 8.1e-8
    d["body"][0]["initial"]["spin_k"] = -1.5
    scene = make(d)
    assert scene.bodies[0].angular_velocity_rad_s[1] == pytest.approx(48.71, abs=0.01)
    result = simulate(scene, cycles=200)
    cone = result.qoi["bodies"]["floator"]["cone_angle_rad"]
    assert result.status == "ok"
    assert cone["mean"] == pytest.approx(0.12962, abs=1e-4)
    assert cone["max"] - cone["min"] < 1e-6
    assert result.qoi["bodies"]["floator"]["cone_angle_closed_form_rad"] == pytest.approx(
        cone["mean"], abs=1e-6
    )


def test_cycle_averaged_force_on_a_pinned_floator_matches_eq_5_71():
    """Floator pinned on the axis of a tilted rotating dipole (Fig. 5.13 scene): the cone is exact
    and the force constant, F_z = 3 mu0 m_R m_F / (4 pi r^4) (cos g sin phi - 2 sin g cos phi):
    Eq. 5.71's PFR term from the cyclic moment minus the coaxial attraction of the static one."""
    scene = load_scene("fig5_13")
    rot, body = scene.rotators[0], scene.bodies[0]
    r, g, m_f = body.position_m[2], rot.tilt_rad, 0.8
    big_m = 1e-7 * rot.moment_Am2 * m_f
    tau_c, tau_s = big_m * math.cos(g) / r**3, 2 * big_m * math.sin(g) / r**3  # Eq. 5.28
    phi = math.atan(tau_c / (0.999e-7 * rot.omega_rad_s**2 - tau_s))  # Eq. 5.24
    assert phi == pytest.approx(0.2154, abs=2e-4)  # the caption's value
    f_z = 3 * big_m / r**4 * (math.cos(g) * math.sin(phi) - 2 * math.sin(g) * math.cos(phi))
    result = simulate(scene, cycles=10)
    force = result.qoi["bodies"]["floator"]["mean_force_N"]
    # at the default N = 64 the cone angle carries an O(h^4) ripple of ~1e-6 rad (see the Eq. 5.7 test)
    assert force[2] == pytest.approx(f_z, rel=1e-5)
    assert abs(force[0]) < 1e-5 * f_z and abs(force[1]) < 1e-5 * f_z


def test_default_integrator_chooses_the_composition_per_scene():
    """issue 28: interacting free bodies run Kahan-Li order 8 (drift <= 1e-12 per 1e4 cycles),
    a driven body keeps splitting4; the choice is recorded in the setting."""
    pair = simulate("mbs_fig6_1", cycles=1000, samples_per_period=8)
    assert pair.integrator == "kahanli8" and pair.setting["chosen_by"].startswith("auto")
    assert pair.setting["steps_per_period"] == 32
    assert max(pair.invariant_drift, pair.momentum_drift, pair.angular_momentum_drift) < 1e-12
    explicit = simulate("mbs_fig6_1", cycles=1000, integrator="splitting4", samples_per_period=8)
    assert explicit.integrator == "splitting4" and "chosen_by" not in explicit.setting
    assert explicit.invariant_drift > 10 * pair.invariant_drift  # the reason for the choice
    one = simulate("conical_5_1", cycles=10)
    assert one.integrator == "splitting4" and one.setting["steps_per_period"] == 64
