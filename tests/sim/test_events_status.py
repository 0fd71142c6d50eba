"""A run never silently returns garbage: contact, escape, blow-up and invariant drift are reported.
Plus the exact damping sub-flow and the closed-form free flight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.sim import simulate

from .conftest import bundled_dict, make


def _attracting_pair(gap_mm: float = 10.0) -> dict:
    """Two coaxial, parallel dipoles released at rest: they attract and touch."""
    body = {
        "mass_g": 5.0,
        "inertia_kg_m2": 1e-8,
        "moment_Am2": 0.5,
        "shape": {"kind": "sphere", "radius_mm": 2.0},
    }
    return {
        "scene": {"name": "pair", "period_s": 0.001, "escape_radius_mm": 500.0},
        "body": [
            dict(body, name="a", initial={"position_mm": [0, 0, 0]}),
            dict(body, name="b", initial={"position_mm": [0, 0, gap_mm]}),
        ],
    }


def test_contact_is_a_terminal_event_with_a_consistent_time():
    scene = make(_attracting_pair())
    # r^-4 forces: the approach is stiff, so N = 128 (h = T/128) rather than the default 64
    a = simulate(scene, cycles=200, steps_per_period=128)
    b = simulate(scene, cycles=200, steps_per_period=256)
    c = simulate(scene, cycles=200, integrator="dop853", rtol=1e-12)
    assert a.status == b.status == c.status == "contact"
    assert "bodies touched" in a.status_detail
    assert a.event_time_s == pytest.approx(b.event_time_s, abs=1e-6 * scene.period())
    assert a.event_time_s == pytest.approx(c.event_time_s, abs=1e-6 * scene.period())
    assert a.times_s[-1] < 200 * scene.period()  # stopped, did not integrate through the singularity
    gap = np.linalg.norm(a.positions_m[-1, 1] - a.positions_m[-1, 0])
    assert gap == pytest.approx(0.004, abs=2e-4)  # contact radii 2 mm + 2 mm


def test_escape_is_reported_within_a_cycle():
    d = bundled_dict("fig5_13")
    d["body"][0]["pinned"] = False
    d["body"][0]["initial"]["velocity_m_s"] = [0.0, 0.0, 2.0]
    d["scene"]["escape_radius_mm"] = 60.0
    scene = make(d)
    result = simulate(scene, cycles=40)
    assert result.status == "escape"
    crossing = (0.060 - 0.030) / 2.0  # at ~2 m/s; the force barely slows it
    assert abs(result.event_time_s - crossing) < 2 * scene.period()


def test_blowup_is_reported():
    d = _attracting_pair(gap_mm=50.0)
    d["body"][1]["initial"]["velocity_m_s"] = [0.0, 2e6, 0.0]
    result = simulate(make(d), cycles=5)
    assert result.status == "blowup"
    assert not result.ok


def test_invariant_drift_above_threshold_is_a_failure(conical):
    result = simulate(conical, cycles=5, steps_per_period=8, drift_threshold=1e-12)
    assert result.status == "invariant_drift"
    assert "jacobi drifted" in result.status_detail


def test_rotational_damping_flow_is_exact():
    """A spinning isotropic body with linear rotational damping: w(t) = w0 exp(-c t / I)."""
    d = {
        "scene": {"name": "spin"},
        "body": [
            {
                "name": "s",
                "mass_g": 1.0,
                "inertia_kg_m2": 1e-7,
                "damping_rot_N_m_s": 2e-8,
                "initial": {"angular_velocity_rad_s": [0.0, 0.0, 500.0]},
            }
        ],
    }
    result = simulate(make(d), cycles=50)
    w = result.angular_velocities_rad_s[:, 0, 2]
    np.testing.assert_allclose(w, 500.0 * np.exp(-0.2 * result.times_s), rtol=1e-12)


def test_uniform_field_scene_moves_the_cm_in_closed_form(conical):
    conical.gravity_m_s2 = np.array([0.0, 0.0, -9.81])
    conical.bodies[0].velocity_m_s = np.array([0.1, 0.0, 0.0])
    result = simulate(conical, cycles=4)
    t = result.times_s
    expected = np.stack([0.1 * t, 0 * t, -0.5 * 9.81 * t**2], axis=1)
    np.testing.assert_allclose(result.positions_m[:, 0], expected, atol=1e-15)
    assert math.isfinite(result.invariant_drift)


@pytest.mark.parametrize("integrator", ["splitting4", "dop853"])
def test_damped_two_bodies_keep_their_energy_budget(integrator):
    """S11: E minus the energy the damping removed stays constant (exact damping sub-flow in the
    splitting; integrated dissipated power in the reference)."""
    d = bundled_dict("mbs_fig6_1")
    d["body"][1]["damping_N_s_m"] = 1e-3
    d["body"][0]["damping_rot_N_m_s"] = 1e-8
    result = simulate(make(d), cycles=50, integrator=integrator, rtol=1e-10)
    assert result.invariant == "energy-budget" and result.status == "ok"
    removed = -result.damping_change[-1]
    assert removed > 0
    energy_scale = abs(result.invariant_values[0])
    assert result.invariant_drift < 1e-8
    assert removed / energy_scale > 1e3 * result.invariant_drift  # the budget term is not negligible


def test_damped_driven_floator_keeps_its_jacobi_budget():
    d = bundled_dict("fig5_13")
    d["body"][0]["pinned"] = False
    d["body"][0]["damping_N_s_m"] = 2e-3
    d["body"][0]["damping_rot_N_m_s"] = 1e-9
    a = simulate(make(d), cycles=20)
    b = simulate(make(d), cycles=20, integrator="dop853", rtol=1e-10)
    assert a.invariant == "jacobi-budget" and a.invariant_drift < 1e-6 and b.invariant_drift < 1e-7
    np.testing.assert_allclose(
        a.qoi["bodies"]["floator"]["mean_force_N"],
        b.qoi["bodies"]["floator"]["mean_force_N"],
        rtol=1e-4,
        atol=1e-9,
    )
