"""Scenes: TOML reading, unit handling, validation errors (file:key: reason), equilibrium helper."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from labkit.errors import LabkitError
from labkit.sim import Scene, SceneBody, SceneError, UniformField, bundled_scenes, load_scene, validate_scene
from labkit.sim.equilibrium import cone_angle_axisymmetric, cone_angle_isotropic

from .conftest import bundled_dict, make


def test_every_bundled_scene_loads():
    names = bundled_scenes()
    assert {"conical_5_1", "fig5_13", "fig5_7", "mbs_fig6_1", "pendulum_5_484", "planar_5_56"} <= set(names)
    for name in names:
        assert load_scene(name).bodies


def test_units_in_key_names_are_converted():
    d = bundled_dict("fig5_13")
    d["body"][0]["mass_kg"] = d["body"][0].pop("mass_g") * 1e-3
    d["rotator"][0]["speed_rpm"] = d["rotator"][0].pop("omega_rad_s") * 60 / (2 * math.pi)
    scene = make(d)
    assert scene.bodies[0].mass_kg == pytest.approx(6.68e-3)
    assert scene.rotators[0].omega_rad_s == pytest.approx(60 * math.pi)
    assert scene.bodies[0].position_m[2] == pytest.approx(0.030)


def _error(d: dict) -> str:
    with pytest.raises(SceneError) as err:
        make(d, "scene.toml")
    assert isinstance(err.value, LabkitError)
    return str(err.value)


def test_unknown_key_names_file_and_key():
    d = bundled_dict("conical_5_1")
    d["body"][0]["mas_g"] = 3.0
    assert _error(d).startswith("scene.toml:body[0].mas_g: unknown key")


def test_zero_mass():
    d = bundled_dict("conical_5_1")
    d["body"][0]["mass_g"] = 0.0
    assert _error(d).startswith("scene.toml:body[0].mass_kg: mass must be positive")


def test_non_positive_definite_inertia():
    d = bundled_dict("conical_5_1")
    d["body"][0]["inertia_kg_m2"] = [[1e-7, 0, 0], [0, -1e-7, 0], [0, 0, 1e-7]]
    assert "not positive definite" in _error(d)


def test_inertia_violating_triangle_inequality():
    d = bundled_dict("conical_5_1")
    d["body"][0]["inertia_kg_m2"] = [1e-7, 1e-7, 3e-7]
    assert "I1 + I2 >= I3" in _error(d)


def test_inconsistent_units():
    d = bundled_dict("conical_5_1")
    d["body"][0]["mass_kg"] = 0.00668
    msg = _error(d)
    assert msg.startswith("scene.toml:body[0].mass_")
    assert "inconsistent units" in msg
    d = bundled_dict("conical_5_1")
    d["field"]["B_c_T"] = 1e-3
    assert "inconsistent units: B_c and tau_c_Nm" in _error(d)


def test_overlapping_bodies():
    d = bundled_dict("mbs_fig6_1")
    d["body"][1]["initial"]["position_mm"] = [0.0, 0.0, 10.0]
    msg = _error(d)
    assert msg.startswith("scene.toml:body[1].initial.position_m: floator overlaps rotator")


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(SceneError, match="no such scene file"):
        load_scene(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene\nname=")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(bad)


def test_python_scene_validated():
    body = SceneBody("b", 1e-3, np.diag([1e-7, 1e-7, 1e-7]), np.array([0, 0, 1.0]))
    scene = Scene("py", [body], field=UniformField("rotating", 1e-3, 0.0, 100.0))
    validate_scene(scene)
    bad = copy.deepcopy(scene)
    bad.bodies[0].mass_kg = -1.0
    with pytest.raises(SceneError, match="mass must be positive"):
        validate_scene(bad)


def test_conical_equilibrium_helper_matches_eq_5_24_and_5_12(conical):
    body = conical.bodies[0]
    omega, tau_c, tau_s, inertia = 80 * math.pi, 1e-3, 4.633e-3, 1e-7
    phi = math.atan(tau_c / (inertia * omega**2 - tau_s))  # Eq. 5.24
    assert phi == pytest.approx(0.536, abs=5e-4)  # the paper's value (Sec. 5.1)
    psi = body.rotation @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(psi, [0.0, -math.sin(phi), math.cos(phi)], atol=1e-15)  # Eq. 5.20, t = 0
    np.testing.assert_allclose(
        body.angular_velocity_rad_s, omega * np.array([0.0, math.sin(phi), 1 - math.cos(phi)]), rtol=1e-14
    )  # Eq. 5.12


def test_cone_angle_sign_flip_and_axisymmetric_limit():
    # tau_S > I w^2 flips the sign of phi (Sec. 5.1: 4.633e-3 and 8e-3 give the same |phi|)
    a = cone_angle_isotropic(omega=80 * math.pi, tau_c=1e-3, tau_s=4.633e-3, inertia=1e-7)
    b = cone_angle_isotropic(omega=80 * math.pi, tau_c=1e-3, tau_s=8e-3, inertia=1e-7)
    assert a == pytest.approx(-b, abs=2e-3)
    # Eq. 5.35 residual vanishes and reduces to Eq. 5.24 for equal moments
    w, tc, ts, ir, ia = 60 * math.pi, 7.5e-4, 0.3 * 7.5e-4, 1.058e-7, 8.099e-8
    phi = cone_angle_axisymmetric(omega=w, tau_c=tc, tau_s=ts, i_radial=ir, i_axial=ia)
    resid = tc * math.cos(phi) + ts * math.sin(phi) - w**2 * math.sin(phi) * (ia + (ir - ia) * math.cos(phi))
    assert abs(resid) < 1e-15
    assert phi == pytest.approx(0.2102, abs=1e-4)  # Table 5.3 row 1, phi-calc column
    assert cone_angle_axisymmetric(omega=w, tau_c=tc, tau_s=ts, i_radial=1e-7, i_axial=1e-7) == pytest.approx(
        cone_angle_isotropic(omega=w, tau_c=tc, tau_s=ts, inertia=1e-7)
    )
