"""Conical motion closed forms (Eq. 5.6-5.35, 5.62-5.68) against the printed matrices, numeric
derivatives and the paper's printed numbers."""

import numpy as np
import pytest

from labkit.model.cone import (
    cone_angle,
    cone_angle_spin,
    cone_angle_tilted_dipole,
    cone_angles_axisymmetric,
    cone_equation_residual,
    conical_angular_velocity,
    conical_axis,
    conical_initial_state,
    conical_rotation,
    rotating_field,
    spin_parameter,
    spin_ratio,
    spin_velocity,
    static_to_cyclic_ratio,
)
from labkit.model.dipole import torque_in_field

W = 80 * np.pi


def test_rotation_matches_eq_5_7_and_axis_eq_5_20():
    phi, t = 0.3, 0.0123
    s, c, cp, sp = np.sin(W * t), np.cos(W * t), np.cos(phi), np.sin(phi)
    printed = np.array([[c * c + s * s * cp, c * s * (1 - cp), s * sp],
                        [c * s * (1 - cp), s * s + c * c * cp, -c * sp],
                        [-s * sp, c * sp, cp]])
    rot = conical_rotation(phi, W, t)
    assert np.allclose(rot, printed, atol=1e-15)
    assert np.allclose(rot[:, 2], conical_axis(phi, W, t))
    assert np.allclose(rot @ rot.T, np.eye(3), atol=1e-15)


@pytest.mark.parametrize("k", [-1.0, 0.0, -1.5, 0.4])
def test_angular_velocity_is_derivative_of_rotation(k):
    """S = R' R^T (Eq. 5.10) by central differences gives Eq. 5.62 (Eq. 5.12 for k = -1)."""
    phi, t, h = 0.25, 0.004, 1e-7
    r_dot = (conical_rotation(phi, W, t + h, k) - conical_rotation(phi, W, t - h, k)) / (2 * h)
    skew = r_dot @ conical_rotation(phi, W, t, k).T
    v = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
    assert np.allclose(v, conical_angular_velocity(phi, W, t, k), rtol=1e-6, atol=1e-6)


def test_paper_pair_of_static_torques_gives_opposite_cone_angles():
    """Below Eq. 5.24: tau_S = 4.633e-3 and 8e-3 give phi = +-0.536 (I=1e-7, w=80 pi, tau_C=1e-3)."""
    assert cone_angle(1e-3, 4.633e-3, 1e-7, W) == pytest.approx(0.536, abs=5e-4)
    assert cone_angle(1e-3, 8e-3, 1e-7, W) == pytest.approx(-0.536, abs=5e-4)


def test_cone_angle_balances_torques_eq_5_23():
    tau_c, tau_s, inertia = 1e-3, 2e-4, 1e-7
    phi = cone_angle(tau_c, tau_s, inertia, W)
    assert tau_c * np.cos(phi) + tau_s * np.sin(phi) == pytest.approx(inertia * W**2 * np.sin(phi))


def test_tilted_dipole_form_equals_eq_5_24_with_eq_5_28():
    tau, gamma = 1.2e-3, 0.1
    assert cone_angle_tilted_dipole(tau, gamma, 1e-7, W) == pytest.approx(
        cone_angle(tau * np.cos(gamma), 2 * tau * np.sin(gamma), 1e-7, W))
    assert static_to_cyclic_ratio(gamma) == pytest.approx(2 * tau * np.sin(gamma) / (tau * np.cos(gamma)))


def test_axisymmetric_root_reduces_to_isotropic_and_solves_eq_5_35():
    iso = cone_angle(1e-3, 2e-4, 1e-7, W)
    same = cone_angles_axisymmetric(tau_c=1e-3, tau_s=2e-4, i_axial=1e-7, i_radial=1e-7, omega=W)
    assert same == pytest.approx(iso)
    phi = cone_angles_axisymmetric(tau_c=7.5e-4, tau_s=2.25e-4, i_axial=8.099e-8, i_radial=1.058e-7,
                                   omega=60 * np.pi)
    assert abs(cone_equation_residual(phi, 7.5e-4, 2.25e-4, 8.099e-8, 1.058e-7, 60 * np.pi)) < 1e-15
    # Table 5.3 row 1 prints phi-calc = 0.2102 (4 decimals)
    assert phi == pytest.approx(0.2102, abs=6e-5)


def test_axisymmetric_root_is_vectorised():
    phis = cone_angles_axisymmetric(tau_c=[7.5e-4, 1e-3], tau_s=[1e-4, 1.3e-4], i_axial=[8.099e-8, 2e-7],
                                    i_radial=[1.058e-7, 1.125e-7], omega=60 * np.pi)
    assert phis.shape == (2,)
    assert phis[1] == pytest.approx(0.2472, abs=6e-5)  # Table 5.3 row 32


def test_spin_closed_form_matches_general_root_and_fig_5_11a():
    """Fig. 5.11(a): q = -0.5 (k = -1.5), I = 8.1e-8, w = 80 pi, tau_C = 1e-3, tau_S = 0: phi = 0.12962."""
    k = spin_parameter(-0.5 * W, W)
    assert k == pytest.approx(-1.5)
    phi = cone_angle_spin(1e-3, 0.0, 8.1e-8, W, k)
    general = cone_angles_axisymmetric(tau_c=1e-3, tau_s=0.0, i_axial=8.1e-8, i_radial=8.1e-8, omega=W, k=k)
    assert phi == pytest.approx(general)
    assert phi == pytest.approx(0.12962, rel=5e-4)
    v = conical_angular_velocity(phi, W, 0.0, k)
    # the caption's |v| = (48.71, 122.28) up to the COMSOL sign convention (Table 5.2)
    assert abs(v[1]) == pytest.approx(48.71, rel=1e-3)
    assert abs(v[2]) == pytest.approx(122.28, rel=3e-3)
    assert spin_ratio(k) == pytest.approx(-0.5)
    assert spin_velocity(k, W) == pytest.approx(-0.5 * W)


def test_initial_state_obeys_eulers_equation_under_the_magnetic_torque():
    """dL/dt of the conical motion (L = I_T v, Eq. 5.15) equals m x B (Eq. 5.22) for the helper's phi."""
    tau_c, tau_s, i_a, i_r = 1e-3, 2e-4, 6e-8, 1.1e-7
    t, h = 0.003, 1e-7

    def momentum(tt):
        return conical_initial_state(tau_c, tau_s, i_a, i_r, W, t=tt).angular_momentum

    state = conical_initial_state(tau_c, tau_s, i_a, i_r, W, t=t)
    dl_dt = (momentum(t + h) - momentum(t - h)) / (2 * h)
    torque = torque_in_field(state.dipole_axis, rotating_field(tau_c, tau_s, W, t))
    assert np.allclose(dl_dt, torque, rtol=1e-6, atol=1e-9)
    assert np.allclose(state.rotation @ state.body_angular_velocity, state.angular_velocity)


def test_a_positional_call_is_refused_not_swapped():
    """The model's and the simulator's cone functions order the same quantities differently:
    both refuse positional calls, and by name they agree."""
    from labkit.sim.equilibrium import cone_angle_axisymmetric, cone_angle_isotropic

    with pytest.raises(TypeError):
        cone_angles_axisymmetric(1e-3, 2e-4, 1e-7, 1e-7, W)  # type: ignore[misc]
    with pytest.raises(TypeError):
        cone_angle_axisymmetric(W, 1e-3, 2e-4, 1e-7, 2e-7)  # type: ignore[misc]
    with pytest.raises(TypeError):
        cone_angle_isotropic(W, 1e-3, 2e-4, 1e-7)  # type: ignore[misc]
    sim = cone_angle_axisymmetric(omega=W, tau_c=1e-3, tau_s=2e-4, i_radial=2e-7, i_axial=1e-7)
    model = cone_angles_axisymmetric(tau_c=1e-3, tau_s=2e-4, i_axial=1e-7, i_radial=2e-7, omega=W)
    assert float(np.asarray(model).ravel()[0]) == pytest.approx(sim, rel=1e-9)
