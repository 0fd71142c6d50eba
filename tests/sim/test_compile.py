"""What a scene compiles to, and the report saying what was kept and dropped."""

from __future__ import annotations

import numpy as np

from labkit.sim import compile_scene, load_scene

from .conftest import bundled_dict, make


def _actions(system) -> dict:
    return {r["item"]: r["action"] for r in system.report}


def test_uniform_field_needs_no_forces():
    system = compile_scene(load_scene("conical_5_1"))
    assert system.kind == "rigid"
    acts = _actions(system)
    assert acts["translation"] == "dropped"
    assert acts["uniform field"] == "kept"
    assert acts["gravity"] == acts["damping"] == acts["body pairs"] == "dropped"
    assert system.invariant == "jacobi"
    assert not system.flags[5] and not system.bi[0, 0]


def test_reduced_one_dof_and_planar_forms_are_detected():
    pend = compile_scene(load_scene("pendulum_5_484"))
    assert pend.kind == "reduced_1dof" and pend.reduced.equation == "Eq. 5.484"
    assert pend.reduced.jc == 1e-3 / 1e-7 and pend.reduced.js == 1.2e-4 / 1e-7
    planar = compile_scene(load_scene("planar_5_56"))
    assert planar.kind == "planar" and planar.reduced.equation == "Eq. 5.56"
    assert planar.invariant == "jacobi"


def test_reduced_form_not_used_when_the_scene_is_not_exactly_that():
    d = bundled_dict("planar_5_56")
    d["body"][0]["initial"]["angular_velocity_rad_s"] = [0.5, 0.0, 48.45]  # spin off the plane's normal
    system = compile_scene(make(d))
    assert system.kind == "rigid"
    assert _actions(system)["reduced forms"] == "not used"


def test_driven_rotator_is_prescribed_and_pinned_body_does_not_translate():
    system = compile_scene(load_scene("fig5_13"))
    acts = _actions(system)
    assert acts["rotator rotator"] == "prescribed"
    assert acts["translation of floator"] == "dropped"
    assert system.flags[1] and system.flags[5] and not system.bi[0, 0]


def test_two_free_bodies_keep_pairs_and_monitor_e_p_j():
    system = compile_scene(load_scene("mbs_fig6_1"))
    acts = _actions(system)
    assert acts["body pairs"] == "kept"
    assert acts["translation of rotator"] == acts["translation of floator"] == "kept"
    assert system.invariant == "energy+momenta"
    assert "symmetric top" in next(r["reason"] for r in system.report if r["item"] == "rotation of rotator")


def test_triaxial_body_uses_dlm_and_gravity_damping_are_kept_when_they_act():
    d = bundled_dict("fig5_13")
    body = d["body"][0]
    body["pinned"] = False
    body["inertia_kg_m2"] = [1.123736e-7, 6.623701e-8, 1.3780954e-7]  # Fig. 5.7 ellipsoid
    body["initial"].pop("equilibrium")
    body["damping_N_s_m"] = 1e-3
    d["gravity"] = {"g_m_s2": [0.0, 0.0, -9.81]}
    system = compile_scene(make(d))
    acts = _actions(system)
    assert "DLM" in next(r["reason"] for r in system.report if r["item"] == "rotation of floator")
    assert acts["gravity"] == "kept" and acts["damping"] == "kept"
    assert system.invariant == "jacobi-budget"  # gravity along the drive axis keeps K; damping is budgeted
    np.testing.assert_allclose(system.g, [0, 0, -9.81])


def test_gravity_dropped_without_translation():
    d = bundled_dict("conical_5_1")
    d["gravity"] = {"g_m_s2": [0.0, 0.0, -9.81]}
    system = compile_scene(make(d))
    assert _actions(system)["gravity"] == "dropped"
    assert system.summary()["kind"] == "rigid"


def test_shifted_rotator_keeps_jacobi_and_ramp_drops_it():
    d = bundled_dict("fig5_13")
    d["rotator"][0]["shift_mm"] = [1.0, 0.0, 0.0]  # dipole off the axis, turning with the rotator
    system = compile_scene(make(d))
    assert system.invariant == "jacobi"
    d["rotator"][0]["ramp_rad_s2"] = 10.0
    system = compile_scene(make(d))
    assert system.invariant == "none" and "ramped" in system.invariant_reason
