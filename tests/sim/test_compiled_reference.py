"""The compiled DOP853 peer (CyRK, numba right-hand side) and scipy's DOP853 on the same RHS.

Both run DOP853 on the same state with the same tolerances, so they must take the same steps
and agree to round-off; both must agree with the splitting reference to their tolerance.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.numerics import metrics
from labkit.sim import SimulationError, compile_scene, load_scene, simulate

pytest.importorskip("CyRK")

KW = {"samples_per_period": 2, "drift_threshold": math.inf, "rotation_threshold": math.inf,
      "attitude": "matrix"}  # the full attitudes, also the turn about an axisymmetric body's axis


@pytest.mark.parametrize("scene_name", ["conical_5_1", "mbs_fig6_1"])
def test_cyrk_and_scipy_dop853_take_the_same_steps(scene_name):
    scene = load_scene(scene_name)
    system = compile_scene(scene)
    cy = simulate(scene, 3, "cyrk-dop853", rtol=1e-9, system=system, **KW)
    sp = simulate(scene, 3, "dop853", rtol=1e-9, system=system, **KW)
    assert cy.status == sp.status == "ok"
    assert cy.n_force_evals == sp.n_force_evals > 100
    scale = system.length_scale
    assert np.max(np.abs(cy.positions_m - sp.positions_m)) / scale < 1e-9
    assert np.max(np.abs(cy.rotations - sp.rotations)) < 1e-9
    assert math.isclose(cy.invariant_drift, sp.invariant_drift, rel_tol=1e-4, abs_tol=1e-15)


@pytest.mark.parametrize("scene_name", ["conical_5_1", "mbs_fig6_1"])
def test_compiled_dop853_converges_to_the_splitting_reference(scene_name):
    scene = load_scene(scene_name)
    system = compile_scene(scene)
    moments = [b.moment_Am2 for b in scene.bodies]
    ref = simulate(scene, 3, "yoshida6", steps_per_period=256, system=system, **KW)
    errors = []
    for rtol in (1e-6, 1e-9, 1e-12):
        run = simulate(scene, 3, "cyrk-dop853", rtol=rtol, system=system, **KW)
        errors.append(metrics.state_errors(run, ref, system.length_scale, system.omega, moments).final)
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-8


def test_compiled_dop853_refuses_reduced_scenes_by_name():
    with pytest.raises(SimulationError, match="rigid-body scenes only"):
        simulate("pendulum_5_484", 1, "cyrk-dop853")
