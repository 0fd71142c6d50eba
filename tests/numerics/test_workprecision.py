"""Work-precision runner: observed orders, cross-checked reference, failures shown, bad input."""

from __future__ import annotations

import math

import pytest

from labkit.numerics import Ladder, NumericsError, reference, require_target, work_precision
from labkit.numerics.checks import check_horizon, check_rtol, check_steps


@pytest.fixture(scope="module")
def report():
    ladder = Ladder(
        steps={"splitting4": [3, 16, 32, 64], "strang": [64, 128, 256]}, rtols={"dop853": [1e-6, 1e-9]}
    )
    return work_precision("conical_5_1", 4, ladder)


def test_observed_orders_match_the_nominal_ones(report):
    assert report.orders["splitting4"]["observed"] == pytest.approx(4.0, abs=0.3)
    assert report.orders["strang"]["observed"] == pytest.approx(2.0, abs=0.3)


def test_reference_is_cross_checked_by_a_second_method(report):
    assert report.reference.cross_checked
    assert report.reference.agreement <= 1e-10
    assert report.reference.dop853_agreement < 1e-7


def test_an_unusable_setting_is_shown_as_failed_not_dropped(report):
    bad = [p for p in report.points if p.setting == "N=3"]
    assert len(bad) == 1 and bad[0].status == "failed" and math.isnan(bad[0].error)
    assert "unstable" in bad[0].message
    assert len(report.points) == 9  # every setting of the ladder has a row


def test_rows_follow_the_issue_schema(report):
    assert set(report.points[0].row()) == {
        "id",
        "integrator",
        "setting",
        "error",
        "invariant_drift",
        "wall_s",
        "n_rhs",
    }


def test_cost_to_reach_and_unreachable_target(report):
    assert report.cost["splitting4"]["0.0001"]["n_rhs"] > 0
    with pytest.raises(NumericsError, match="no setting of the sweep reaches error 1e-13"):
        require_target(report, 1e-13)


def test_bad_inputs_end_with_clear_messages():
    with pytest.raises(NumericsError, match="below what double precision"):
        check_rtol(1e-16)
    with pytest.raises(NumericsError, match="cannot reach the requested error"):
        check_rtol(1e-6, target_error=1e-9)
    with pytest.raises(NumericsError, match="at least 7 steps per period"):
        check_steps(4, 251.0, 500.0)
    with pytest.raises(NumericsError, match="round-off"):
        check_steps(1024, 1.0, 1.0, target_error=1e-14, cycles=1e6)
    with pytest.raises(NumericsError, match="GiB for the samples"):
        check_horizon(1e9, 8, 2)
    with pytest.raises(NumericsError, match="GiB"):
        reference("conical_5_1", 1e10)
