"""Heuristic criterion Eq. 5.36-5.46 against Table 5.3's printed minimum ratios and Fig. 5.2."""

import numpy as np
import pytest

from labkit.model.cone import cone_angle
from labkit.model.stability import (
    criterion_holds,
    equilibrium_function,
    min_static_ratio,
    min_static_torque,
    stability_term,
)
from labkit.reproduce.paper_data import TABLE_5_3


@pytest.mark.parametrize("row", TABLE_5_3, ids=lambda r: f"row{r[0]}")
def test_min_ratio_column_of_table_5_3(row):
    """'Min tau_S/tau_C' is printed to 3 decimals: tolerance 6e-4."""
    _, _, i_r, omega, tau_c, _, printed, *_ = row
    assert min_static_ratio(tau_c, i_r, omega) == pytest.approx(printed, abs=6e-4)


def test_fig_5_2_ratios():
    """Fig. 5.2: w = 60 pi, J_C = 11000: ratios 0.16-0.20 stable, 0.15 and below not."""
    w, inertia = 60 * np.pi, 1e-7
    tau_c = 11000 * inertia
    for ratio, stable in [(0.20, True), (0.16, True), (0.15, False), (0.11, False)]:
        assert bool(criterion_holds(tau_c, ratio * tau_c, inertia, w)) is stable


def test_boundary_is_the_minimum_torque():
    tau_c, inertia, w = 1e-3, 1e-7, 70 * np.pi
    t_min = min_static_torque(tau_c, inertia, w)
    assert not criterion_holds(tau_c, t_min * (1 - 1e-9), inertia, w)
    assert criterion_holds(tau_c, t_min * (1 + 1e-6), inertia, w)


def test_slope_at_equilibrium_is_u_eq_5_40():
    j_c, j_s, w = 1e4, 2e3, 60 * np.pi
    phi_e = cone_angle(j_c, j_s, 1.0, w)
    assert equilibrium_function(phi_e, j_c, j_s, w) == pytest.approx(0.0, abs=1e-9)
    u = np.hypot(j_c, w**2 - j_s)
    assert stability_term(phi_e, j_c, j_s, w) == pytest.approx(w**2 - u)
