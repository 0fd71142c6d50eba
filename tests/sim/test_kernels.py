"""Compiled force/torque kernels against labkit.model.dipole (Eq. 4.1-4.3) and against physics:
force = -grad U, Newton's third law and conservation of total angular momentum for a pair."""

from __future__ import annotations

import numpy as np
import pytest

from labkit.sim import compile_scene, load_scene
from labkit.sim.integrators import kernels as K

rng = np.random.default_rng(7)
CASES = [(rng.normal(size=3), rng.normal(size=3), rng.normal(size=3) * 0.02) for _ in range(20)]


@pytest.mark.parametrize("m_a, m_b, r", CASES)
def test_kernels_match_labkit_model(m_a, m_b, r):
    dipole = pytest.importorskip("labkit.model.dipole")
    f = np.array(K.dipole_force_torque(*m_a, *m_b, *r))
    np.testing.assert_allclose(f[:3], dipole.dipole_force(m_a, m_b, r), rtol=1e-12)
    np.testing.assert_allclose(
        f[3:], dipole.dipole_torque(m_a, m_b, r), rtol=1e-12, atol=1e-14 * np.abs(f[3:]).max()
    )
    np.testing.assert_allclose(K.dipole_field(*m_a, *r), dipole.dipole_field(m_a, r), rtol=1e-12)


@pytest.mark.parametrize("m_a, m_b, r", CASES[:5])
def test_force_is_minus_gradient_and_torque_is_m_cross_b(m_a, m_b, r):
    def energy(p):
        return -np.dot(m_b, K.dipole_field(*m_a, *p))

    h = 1e-7 * np.linalg.norm(r)
    grad = np.array([(energy(r + e) - energy(r - e)) / (2 * h) for e in np.eye(3) * h])
    f = np.array(K.dipole_force_torque(*m_a, *m_b, *r))
    np.testing.assert_allclose(f[:3], -grad, rtol=1e-6)
    np.testing.assert_allclose(f[3:], np.cross(m_b, K.dipole_field(*m_a, *r)), rtol=1e-12)


def test_pair_forces_conserve_momentum_and_angular_momentum():
    system = compile_scene(load_scene("mbs_fig6_1"))
    x = system.x0 + rng.normal(size=(2, 3)) * 1e-3
    R = system.R0.copy()
    bf = system.bf.copy()
    bf[:, 7:10] = [[1e-3, -2e-3, 0.5e-3], [0.0, 1e-3, -1e-3]]  # dipole offsets from the CM
    F, T = np.zeros((2, 3)), np.zeros((2, 3))
    K.compute_forces(0.0, x, R, bf, system.bi, system.src, system.fld, system.flags, F, T, K.workspace(2))
    np.testing.assert_allclose(F[0], -F[1], rtol=1e-13)
    total = T.sum(axis=0) + np.cross(x[0], F[0]) + np.cross(x[1], F[1])
    assert np.linalg.norm(total) < 1e-12 * np.abs(T).max()


def test_rotator_moment_and_shift_follow_eq_5_25():
    src = np.zeros((1, K.SRC_WIDTH))
    src[0, :5] = [2.0, 0.3, 100.0, 0.2, 4.0]  # moment, tilt, omega, phase, ramp
    src[0, 5:8] = [1e-3, 2e-3, 0.5e-3]  # shift in the rotator frame
    src[0, 8:11] = [0.0, 0.0, -0.01]
    t = 0.013
    th = 0.2 + 100.0 * t + 0.5 * 4.0 * t * t
    state = np.array(K.source_state(src, 0, t))
    expected_m = 2.0 * np.array([np.cos(0.3) * np.sin(th), -np.cos(0.3) * np.cos(th), np.sin(0.3)])
    c, s = np.cos(th), np.sin(th)
    expected_p = np.array([c * 1e-3 - s * 2e-3, s * 1e-3 + c * 2e-3, 0.5e-3 - 0.01])
    np.testing.assert_allclose(state[:3], expected_m, rtol=1e-14)
    np.testing.assert_allclose(state[3:], expected_p, rtol=1e-14, atol=1e-18)
