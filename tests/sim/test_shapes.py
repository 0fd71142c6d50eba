"""Specialised step kernels give the general kernel's results; named status codes."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

import labkit
from labkit.sim import compile_scene, load_scene, scene_from_dict, simulate
from labkit.sim.integrators import splitting_run
from labkit.sim.integrators.shapes import scene_shape
from labkit.sim.integrators.splitting import COMPOSITIONS
from labkit.sim.integrators.status import LABELS, MESSAGES, Status


@pytest.mark.parametrize(("scene_name", "shape"), [("conical_5_1", "fixed_top"), ("fig5_13", "fixed_top"),
                                                   ("mbs_fig6_1", "free_pair"), ("fig5_7", "general")])
def test_each_bundled_scene_gets_its_kernel(scene_name, shape):
    system = compile_scene(load_scene(scene_name))
    assert scene_shape(system) == shape
    assert simulate(scene_name, 1, system=system).setting["kernel"] == shape


def _top_scene(field: dict, rotators: list, inertia: list) -> dict:
    """A pinned symmetric top (unequal axial moment: the body-axis turn of the free rotation runs)
    off the drive axis, with an offset dipole not on its symmetry axis."""
    return {
        "scene": {"name": "top", "cycles": 5},
        "field": field,
        "rotator": rotators,
        "body": [{"name": "top", "mass_g": 5.0, "inertia_kg_m2": inertia, "pinned": True,
                  "moment_vector_Am2": [0.1, 0.0, 0.8], "dipole_offset_mm": [0.3, 0.0, 1.0],
                  "initial": {"position_mm": [3.0, 2.0, 30.0], "euler_zxz_rad": [0.3, 0.4, 0.1],
                              "angular_velocity_rad_s": [5.0, -3.0, 80.0]}}],
    }


#: fixed-top scenes beyond the bundled ones: a rotating field with two rotators (one shifted off
#: its axis, one ramped, another axis point), and an oscillating field alone
TOP_SCENES = {
    "field_and_rotators": _top_scene(
        {"kind": "rotating", "omega_rad_s": 100.0, "B_c_mT": 1.0, "B_s_mT": 3.0},
        [{"name": "r1", "moment_Am2": 0.25, "omega_rad_s": 100.0, "tilt_rad": 0.1,
          "shift_mm": [1.0, 0.5, 0.2]},
         {"name": "r2", "moment_Am2": 0.1, "omega_rad_s": 100.0, "ramp_rad_s2": 3.0, "tilt_rad": -0.2,
          "axis_point_mm": [40.0, 0.0, 0.0]}],
        [1e-7, 1e-7, 1.6e-7]),
    "oscillating_field": _top_scene(
        {"kind": "oscillating", "omega_rad_s": 150.0, "B_c_mT": 2.0, "B_s_mT": 1.0}, [],
        [1e-7, 1e-7, 0.7e-7]),
}


def _both_kernels(system, shape: str, cycles: int):
    weights = COMPOSITIONS["suzuki4"][0]
    h = system.period / 64
    n = 64 * cycles
    runs = [splitting_run._integrate_rigid(system, weights, kernel, 0.0, h, n, 8, n // 8 + 2)
            for kernel in ("general", shape)]
    (s_g, _, n_g, t_g, g), (s_f, _, n_f, t_f, f) = runs
    assert s_g == s_f == Status.OK and n_g == n_f == len(weights) * n + 1
    assert np.array_equal(t_g, t_f)
    return g, f


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))


@pytest.mark.parametrize(("scene_name", "shape"), [("conical_5_1", "fixed_top"), ("fig5_13", "fixed_top"),
                                                   ("mbs_fig6_1", "free_pair")])
def test_specialised_kernel_matches_the_general_kernel(scene_name, shape):
    """Round-off apart: ``fixed_top`` turns the drive phases of a step's stages by products where
    the general kernel takes cos and sin of each stage's time, so the two runs separate as
    round-off grows (1e-11 in R after 50 cycles of conical_5_1, as a 1e-15 change of L0 does); a
    wrong or missing term separates them by orders of magnitude more."""
    g, f = _both_kernels(compile_scene(load_scene(scene_name)), shape, 50)
    assert np.max(np.abs(g["R"] - f["R"])) < 1e-10
    assert _relative(g["x"], f["x"]) <= 1e-10
    assert _relative(g["L"], f["L"]) <= 1e-10
    assert _relative(g["impulse"], f["impulse"]) <= 1e-10


@pytest.mark.parametrize("name", sorted(TOP_SCENES))
def test_fixed_top_kernel_matches_the_general_kernel_on_other_tops(name):
    """Both scenes are chaotic (a 1e-15 change of L0 grows to 1e-7..1e-1 in R over 50 cycles), so
    they are compared over 5 cycles, where round-off has grown to ~1e-12."""
    system = compile_scene(scene_from_dict(TOP_SCENES[name], source=f"<{name}>"))
    assert scene_shape(system) == "fixed_top"
    g, f = _both_kernels(system, "fixed_top", 5)
    assert np.max(np.abs(g["R"] - f["R"])) < 1e-10
    assert _relative(g["L"], f["L"]) <= 1e-10
    assert _relative(g["impulse"], f["impulse"]) <= 1e-10


def test_every_status_has_a_label_and_a_message():
    assert [int(s) for s in Status] == [0, 1, 2, 3, 4, 5]
    assert set(LABELS) == set(MESSAGES) == set(Status)
    text = MESSAGES[Status.ESCAPE].format(r_escape=0.5, message="")
    assert text == "a body went beyond 0.5 m from the others"


def _pair_released(z_mm: float, vz_m_s: float, escape_mm: float | None = None) -> dict:
    """``mbs_fig6_1`` with its floator released on the axis at ``z_mm`` moving at ``vz_m_s``."""
    data = tomllib.loads((Path(labkit.__file__).parent / "data/scenes/mbs_fig6_1.toml").read_text())
    initial = data["body"][1]["initial"]
    del initial["equilibrium"]
    initial["position_mm"] = [0.0, 0.0, z_mm]
    initial["velocity_m_s"] = [0.0, 0.0, vz_m_s]
    if escape_mm is not None:
        data["scene"]["escape_radius_mm"] = escape_mm
    return data


@pytest.mark.parametrize(("released", "status"), [((20.0, -2.0), Status.CONTACT),
                                                  ((40.0, 3.0, 100.0), Status.ESCAPE)])
def test_free_pair_kernel_ends_at_the_general_kernels_event(released, status):
    """The free_pair kernel keeps its state in local variables within a step; the contact and
    escape checks after each step must still see it (same event, time and last state)."""
    system = compile_scene(scene_from_dict(_pair_released(*released)))
    assert scene_shape(system) == "free_pair"
    weights = COMPOSITIONS["kahanli8"][0]
    h = system.period / 32
    n = 32 * 50
    (s_g, e_g, n_g, t_g, g), (s_f, e_f, n_f, t_f, f) = [
        splitting_run._integrate_rigid(system, weights, kernel, 0.0, h, n, 8, n // 8 + 2)
        for kernel in ("general", "free_pair")]
    assert s_g == s_f == status
    assert n_g == n_f < len(weights) * n
    assert e_f == pytest.approx(e_g, rel=1e-12)
    assert np.array_equal(t_g, t_f)
    assert _relative(g["x"], f["x"]) <= 1e-12
    assert _relative(g["v"], f["v"]) <= 1e-12
    assert np.max(np.abs(g["R"] - f["R"])) < 1e-12
