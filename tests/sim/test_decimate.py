"""Decimated samples: every K-th sample of the full run (and the last), same invariant budget."""

from __future__ import annotations

import numpy as np
import pytest

from labkit.cli import main
from labkit.sim import SimulationError, simulate


@pytest.mark.parametrize("integrator", ["splitting4", "cyrk-dop853"])
def test_decimated_samples_are_a_subset_of_the_full_run(integrator):
    if integrator.startswith("cyrk"):
        pytest.importorskip("CyRK")
    full = simulate("mbs_fig6_1", 10, integrator, samples_per_period=4)
    thin = simulate("mbs_fig6_1", 10, integrator, samples_per_period=4, decimate=3)
    assert len(full.times_s) == 41
    keep = list(range(0, 41, 3)) + [40]
    assert np.allclose(thin.times_s, full.times_s[keep], rtol=0, atol=1e-15)
    assert np.allclose(thin.positions_m, full.positions_m[keep], rtol=1e-9, atol=1e-15)
    assert thin.invariant_drift <= full.invariant_drift * (1 + 1e-6)
    assert thin.setting.get("decimate", 3) == 3


def test_bad_decimate_fails_with_one_line(capsys):
    with pytest.raises(SimulationError, match="decimate must be a whole number"):
        simulate("conical_5_1", 1, decimate=0)
    assert main(["simulate", "conical_5_1", "--cycles", "1", "--decimate", "0"]) == 2
    assert "decimate must be a whole number" in capsys.readouterr().err
