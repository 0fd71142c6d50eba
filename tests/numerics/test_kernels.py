"""The batch kernels against labkit.sim's splitting integrator, each other, and the invariant."""

from __future__ import annotations

import numpy as np
import pytest

from labkit.numerics import kernels, stability_map
from labkit.numerics.stress import I_S1, OMEGA_S1, s1_like
from labkit.sim import load_scene, simulate


def test_numba_kernel_matches_the_simulator_on_the_same_scheme():
    scene = load_scene("conical_5_1")
    res = kernels.run_batch_numba(kernels.spec_from_scenes([scene]), 50, 64, 8)
    sim = simulate(scene, 50, steps_per_period=64, samples_per_period=8)
    zen = np.arccos(np.clip(sim.dipole_directions()[:, 2], -1, 1))
    # the same splitting in other units: agreement is at round-off level, far below its 2e-6 error
    assert np.max(np.abs(zen - res.zenith[0])) < 1e-11


def test_numpy_batch_equals_numba_batch():
    spec, _ = stability_map.batch_spec(stability_map.table5_3_rows()[:6])
    a = kernels.run_batch_numba(spec, 3, 32, 2)
    b = kernels.run_batch_numpy(spec, 3, 32, 2)
    np.testing.assert_allclose(a.zenith, b.zenith, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.jacobi, b.jacobi, rtol=0, atol=1e-12)


def test_jacobi_invariant_drift_is_bounded_on_a_short_run():
    spec = kernels.spec_from_scenes([load_scene("conical_5_1")])
    res = kernels.run_batch_numba(spec, 300, 64, 1)
    k = res.jacobi[0]
    assert np.max(np.abs(k - k[0])) / abs(k[0]) < 1e-10  # NUMERICS.md T1 at a tenth of the horizon


@pytest.mark.parametrize("inertia, omega", [(1e-12, 11_000.0), (1e-6, 100.0)])
def test_si_runs_agree_with_the_nondimensional_kernel(inertia, omega):
    """T7: the same tau / (I w^2) at very different I and w is the same ODE."""
    nd = kernels.run_batch_numba(kernels.spec_from_scenes([s1_like(I_S1, OMEGA_S1)]), 30, 64, 8)
    si = simulate(s1_like(inertia, omega), 30, steps_per_period=64, samples_per_period=8)
    zen = np.arccos(np.clip(si.dipole_directions()[:, 2], -1, 1))
    assert np.max(np.abs(zen - nd.zenith[0])) < 1e-10
    assert np.max(np.abs(si.invariant_values / (inertia * omega**2) - nd.jacobi[0])) < 1e-10


def test_fast_kernel_refuses_scenes_it_cannot_run():
    with pytest.raises(ValueError, match="one body in a rotating uniform field"):
        kernels.spec_from_scenes([load_scene("mbs_fig6_1")])
    with pytest.raises(ValueError, match="multiple"):
        kernels.run_batch_numba(kernels.spec_from_scenes([load_scene("conical_5_1")]), 1, 10, 3)
