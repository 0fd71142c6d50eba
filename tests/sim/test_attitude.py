"""What a run stores of each body's attitude (docs/decisions/0015-store-what-the-scene-needs.md):
an axisymmetric body its axis, any other body its rotation matrix, every matrix on request."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.sim import SimulationError, load_scene, simulate
from labkit.sim.attitude import body_axis, shortest_turns
from labkit.sim.rotations import axis_angle

unit = st.tuples(*[st.floats(-1, 1)] * 3).map(np.array).filter(lambda v: np.linalg.norm(v) > 0.1)


def test_an_axisymmetric_body_keeps_its_axis_and_the_same_numbers():
    axis_run = simulate("conical_5_1", cycles=20)
    full = simulate("conical_5_1", cycles=20, attitude="matrix")
    assert axis_run.axis_only == ["floator"] and axis_run.rotation_matrices == {}
    assert full.axis_only == [] and set(full.rotation_matrices) == {0}
    # the axis is the full run's rotation applied to the body's axis (its dipole, body z)
    np.testing.assert_allclose(axis_run.axis_body[0], [0.0, 0.0, 1.0])
    np.testing.assert_allclose(axis_run.axes[:, 0], full.rotation(0) @ axis_run.axis_body[0], atol=1e-15)
    np.testing.assert_array_equal(axis_run.angular_velocities_rad_s, full.angular_velocities_rad_s)
    assert axis_run.qoi == full.qoi and axis_run.invariant_drift == full.invariant_drift
    # 3 numbers per sample instead of 9
    assert axis_run.axes[:, 0].nbytes * 3 == full.rotation(0).nbytes


def test_asking_an_axis_only_body_for_its_rotation_fails_clearly():
    result = simulate("conical_5_1", cycles=2)
    with pytest.raises(ValueError, match="'floator' is axisymmetric.*attitude='matrix'"):
        result.rotations  # noqa: B018
    with pytest.raises(ValueError, match="not along it"):
        result.dipole_directions(0, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(result.dipole_directions(0, [0.0, 0.0, -2.0]), -result.axes[:, 0])


def test_display_rotations_carry_the_axis_and_are_rotations():
    result = simulate("conical_5_1", cycles=2)
    shown = result.display_rotations(0)
    np.testing.assert_allclose(shown @ result.axis_body[0], result.axes[:, 0], atol=1e-14)
    gram = np.einsum("nji,njk->nik", shown, shown)
    np.testing.assert_allclose(gram, np.broadcast_to(np.eye(3), shown.shape), atol=1e-14)
    t, poses = next(iter(result.poses()))
    np.testing.assert_allclose(poses["floator"][1], shown[0])


def test_a_body_with_three_unequal_moments_keeps_its_matrix():
    scene = copy.deepcopy(load_scene("conical_5_1"))
    scene.bodies[0].inertia_kg_m2 = np.diag([1.0e-7, 1.3e-7, 1.6e-7])
    result = simulate(scene, cycles=2, drift_threshold=1.0)
    assert result.axis_only == [] and result.rotations.shape == (len(result.times_s), 1, 3, 3)
    np.testing.assert_allclose(result.axes[:, 0], result.rotations[:, 0] @ [0.0, 0.0, 1.0], atol=1e-15)


def test_json_names_each_body_attitude_and_series_hold_axes():
    doc = simulate("mbs_fig6_1", cycles=2).to_json(series=True)
    # the rotor's dipole is across its spin axis: not axisymmetric
    assert doc["attitude"] == {"rotator": "matrix", "floator": "axis"}
    assert set(doc["series"]["rotations"]) == {"rotator"}
    assert np.asarray(doc["series"]["axes"]).shape == (len(doc["series"]["times_s"]), 2, 3)


def test_an_unknown_attitude_is_refused():
    with pytest.raises(SimulationError, match="attitude must be one of axis, matrix"):
        simulate("conical_5_1", cycles=1, attitude="quaternion")


@pytest.mark.parametrize("inertia, moment, offset, axisymmetric", [
    (np.diag([1.0, 1.0, 2.0]), [0, 0, 1.0], [0, 0, 0], True),      # disc magnet, poles on its faces
    (np.diag([1.0, 1.0, 2.0]), [1.0, 0, 0], [0, 0, 0], False),      # dipole across the symmetry axis
    (np.diag([1.0, 1.0, 2.0]), [0, 0, 1.0], [1e-3, 0, 0], False),   # dipole off the axis
    (np.diag([1.0, 1.0, 2.0]), [0, 0, 1.0], [0, 0, 1e-3], True),    # dipole shifted along the axis
    (np.eye(3), [1.0, 0, 0], [0, 0, 0], True),                       # sphere: symmetric about its dipole
    (np.diag([1.0, 1.5, 2.0]), [0, 0, 1.0], [0, 0, 0], False),      # three unequal moments
    (np.diag([2.0, 1.0, 1.0]), [0, 0, 0], [0, 0, 0], True),         # no dipole: the symmetry axis (x)
])
def test_which_bodies_are_axisymmetric(inertia, moment, offset, axisymmetric):
    axis, symmetric = body_axis(inertia, np.array(moment, float), np.array(offset, float))
    assert symmetric == axisymmetric
    assert np.linalg.norm(axis) == pytest.approx(1.0)


@settings(max_examples=60, deadline=None)
@given(unit, st.floats(0.1, 3.0), unit, st.floats(0.0, 6.3), st.floats(0.2, 5.0), st.booleans())
def test_axisymmetry_does_not_depend_on_the_body_frame(u, ratio, turn_axis, angle, scale, tilt_moment):
    """Turning a body's frame turns its axis with it and keeps the verdict."""
    u = u / np.linalg.norm(u)
    inertia = scale * (np.eye(3) + (ratio - 1.0) * np.outer(u, u))
    moment = np.cross(u, [0.3, 0.5, 0.7]) if tilt_moment else 2.0 * u
    if np.linalg.norm(moment) < 1e-3:
        return
    q = axis_angle(turn_axis, angle)
    axis, symmetric = body_axis(inertia, moment, np.zeros(3))
    turned_axis, turned_symmetric = body_axis(q @ inertia @ q.T, q @ moment, np.zeros(3))
    assert symmetric == turned_symmetric == (not tilt_moment or abs(ratio - 1.0) < 1e-9)
    np.testing.assert_allclose(turned_axis, q @ axis, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(unit, st.lists(unit, min_size=1, max_size=5), st.booleans())
def test_shortest_turns_take_the_axis_where_it_points(a, targets, opposite):
    a = a / np.linalg.norm(a)
    b = np.array([t / np.linalg.norm(t) for t in targets])
    if opposite:
        b[0] = -a
    r = shortest_turns(a, b)
    np.testing.assert_allclose(r @ a, b, atol=1e-12)
    gram = np.einsum("nji,njk->nik", r, r)
    np.testing.assert_allclose(gram, np.broadcast_to(np.eye(3), r.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-12)
