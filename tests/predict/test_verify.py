"""Time-domain check with labkit.sim: the predicted equilibrium holds, an unstable one does not."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from scipy.optimize import brentq

from labkit.predict.pair import ForceCurve
from labkit.predict.verify import verify

from .conftest import RPM

OMEGA = 25000 * RPM


@pytest.fixture(scope="module")
def curve(story_pair):
    return ForceCurve(story_pair, OMEGA)


def test_predicted_equilibrium_stays_bound(story_pair, curve):
    bs = curve.bound_state()
    ver = verify(story_pair, OMEGA, curve.state(bs.r_eq), cycles=1000)
    assert ver.status == "ok" and ver.bound
    assert ver.invariant == "jacobi" and ver.invariant_drift < 1e-6
    # started on the co-rotating steady state, the mean axial distance is the solved one
    assert ver.distance_mean_m == pytest.approx(bs.r_eq, rel=1e-5)
    # the axial oscillation gives the stiffness independently of the force derivative; the two
    # differ by the cone's dynamic response (a few %), not by orders of magnitude
    assert ver.axial.stiffness == pytest.approx(bs.stiffness, rel=0.15)
    # lateral: one forward and one backward whirl, their product positive (stable)
    w_plus, w_minus = ver.lateral.frequencies
    assert w_plus > 0 > w_minus
    assert ver.lateral.stiffness > 0


def test_floator_above_the_rotator_stays_bound_too(story_pair):
    # the above-rotator state is the point inversion of the beneath one; weight now pushes inward
    above = replace(story_pair, placement="above")
    curve = ForceCurve(above, OMEGA)
    bs = curve.bound_state()
    ver = verify(above, OMEGA, curve.state(bs.r_eq), cycles=500)
    assert ver.status == "ok" and ver.bound
    assert ver.distance_mean_m == pytest.approx(bs.r_eq, rel=1e-5)


def test_equilibrium_on_the_unstable_branch_is_lost(story_pair, curve):
    bs = curve.bound_state()
    # the second root of F + m g = 0, beyond the stiffness limit: S < 0 there (Eq. 6.19)
    r_bad = brentq(lambda r: curve(r) + story_pair.load, bs.r_limit, 5 * bs.r_limit, xtol=1e-12)
    assert -(curve(r_bad * 1.001) - curve(r_bad * 0.999)) < 0
    ver = verify(story_pair, OMEGA, curve.state(r_bad), cycles=1000)
    assert not ver.bound
    assert ver.status in ("contact", "escape") or not math.isclose(ver.distance_mean_m, r_bad, rel_tol=0.25)
