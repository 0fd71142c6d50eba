"""The axial bound-state solver on the paper's force law Eq. 6.21 (cm, N) and its numbers below
Eq. 6.22: S > 0 for r < 4.26 cm, largest load 0.117 N, stiffness 48.7 / 61.9 / 35.1 N/m for a
4 g floator weightless / above / beneath the rotator."""

from __future__ import annotations

import pytest

from labkit.predict.axial import axial_bound_state, stiffness

G0 = 9.80665
WEIGHT = 0.004 * G0


def eq6_21(r_m: float) -> float:
    r = 100.0 * r_m  # cm
    return 3950.0 * r**-7 - 89.5 * r**-4


def test_stiffness_limit_and_largest_load():
    bs = axial_bound_state(eq6_21, 0.0, 0.01, 0.2)
    assert bs.r_limit * 100 == pytest.approx(4.26, abs=0.005)
    assert bs.max_load == pytest.approx(0.117, abs=0.0005)


@pytest.mark.parametrize("load, paper", [(0.0, 48.7), (-WEIGHT, 61.9), (WEIGHT, 35.1)])
def test_stiffness_at_equilibrium(load, paper):
    bs = axial_bound_state(eq6_21, load, 0.01, 0.2)
    assert bs.bound
    assert bs.stiffness == pytest.approx(paper, abs=0.05)
    assert bs.stiffness_error < 1e-3
    assert eq6_21(bs.r_eq) + load == pytest.approx(0.0, abs=bs.stiffness * bs.r_eq_error * 2)


def test_weightless_equilibrium_is_where_the_curves_cross():
    bs = axial_bound_state(eq6_21, 0.0, 0.01, 0.2)
    assert bs.r_eq * 100 == pytest.approx((3950 / 89.5) ** (1 / 3), rel=1e-8)  # 3.53 cm in the paper


def test_stiffness_derivative_against_eq6_22():
    r = 0.035
    s = stiffness(eq6_21, r)
    rc = 100 * r
    assert s.value == pytest.approx(100 * (27650 * rc**-8 - 358 * rc**-5), rel=1e-3)


def test_too_heavy_and_snapping():
    heavy = axial_bound_state(eq6_21, 0.2, 0.01, 0.2)
    assert not heavy.bound and "exceeds the largest net attraction" in heavy.reason
    snap = axial_bound_state(eq6_21, 0.0, 0.036, 0.2)  # contact beyond the equilibrium
    assert not snap.bound and "snap" in snap.reason
