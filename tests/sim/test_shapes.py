"""Specialised step kernels give the general kernel's results; named status codes."""

from __future__ import annotations

import numpy as np
import pytest

from labkit.sim import compile_scene, load_scene, simulate
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


@pytest.mark.parametrize(("scene_name", "shape"), [("conical_5_1", "fixed_top"), ("fig5_13", "fixed_top"),
                                                   ("mbs_fig6_1", "free_pair")])
def test_specialised_kernel_matches_the_general_kernel(scene_name, shape):
    system = compile_scene(load_scene(scene_name))
    weights = COMPOSITIONS["suzuki4"][0]
    h = system.period / 64
    n = 64 * 50
    runs = [splitting_run._integrate_rigid(system, weights, shape, 0.0, h, n, 8, n // 8 + 2)
            for kernel in ("general", shape)]
    (s_g, _, n_g, t_g, g), (s_f, _, n_f, t_f, f) = runs
    assert s_g == s_f == Status.OK and n_g == n_f == len(weights) * n + 1
    assert np.array_equal(t_g, t_f)
    # same arithmetic in the same order: equal to a few ulps after 12800 stages
    assert np.max(np.abs(g["R"] - f["R"])) < 1e-12
    assert np.max(np.abs(g["x"] - f["x"])) <= 1e-12 * max(np.max(np.abs(g["x"])), 1e-300)
    assert np.max(np.abs(g["L"] - f["L"])) <= 1e-12 * np.max(np.abs(g["L"]))
    assert np.max(np.abs(g["impulse"] - f["impulse"])) <= 1e-12 * max(np.max(np.abs(g["impulse"])), 1e-300)


def test_every_status_has_a_label_and_a_message():
    assert [int(s) for s in Status] == [0, 1, 2, 3, 4, 5]
    assert set(LABELS) == set(MESSAGES) == set(Status)
    text = MESSAGES[Status.ESCAPE].format(r_escape=0.5, message="")
    assert text == "a body went beyond 0.5 m from the others"
