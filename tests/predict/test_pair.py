"""The dipole pair: bound / no bound, speed limits, and the Fig. 5.26 / Eq. 6.18 scaling."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from labkit.predict.pair import ForceCurve, min_speed, scaled_min_speed_guess, speed_for_distance
from labkit.predict.predictor import scaled_floator

from .conftest import RPM

STORY_OMEGA = 25000 * RPM


@pytest.fixture(scope="module")
def story_state(story_pair):
    curve = ForceCurve(story_pair, STORY_OMEGA)
    return curve, curve.bound_state()


def test_story_binds_between_contact_and_stiffness_limit(story_pair, story_state):
    curve, bs = story_state
    assert bs.bound
    assert story_pair.contact_distance < bs.r_eq < bs.r_limit
    assert bs.stiffness > 0
    # the weight is carried: net attraction at r_eq equals m g (Eq. 6.19)
    assert -curve(bs.r_eq) == pytest.approx(story_pair.floator.mass_kg * 9.80665, rel=1e-6)


def test_static_attraction_matches_the_on_axis_closed_form(story_pair, story_state):
    # pinned-floator closed form (Fig. 5.13 scene): F_static = -6 M sin(g) cos(phi) / r^4; the
    # steady state's lateral circle (beta << r) changes it only a little
    curve, bs = story_state
    st = curve.state(bs.r_eq)
    closed = -6 * story_pair.dipole_constant * math.sin(story_pair.gamma) * math.cos(st.phi) / bs.r_eq**4
    assert st.force_static_z == pytest.approx(closed, rel=0.02)


def test_weight_above_moves_the_floator_closer(story_pair, story_state):
    above = ForceCurve(replace(story_pair, placement="above"), STORY_OMEGA).bound_state()
    assert above.bound and above.r_eq < story_state[1].r_eq


def test_no_tilt_means_no_attraction_and_no_bound_state(story_pair):
    bs = ForceCurve(replace(story_pair, gamma=0.0), STORY_OMEGA).bound_state()
    assert not bs.bound
    assert "exceeds the largest net attraction" in bs.reason


def test_speed_limits_bracket_the_bound_state(story_pair, story_state):
    w_max = speed_for_distance(story_pair, story_pair.contact_distance, STORY_OMEGA, rtol=1e-5)
    guess = scaled_min_speed_guess(story_state[0])
    w_min = min_speed(story_pair, STORY_OMEGA, rtol=1e-5, guess=guess)
    assert w_min < STORY_OMEGA < w_max
    assert ForceCurve(story_pair, 1.02 * w_min).bound_state(1e-8).bound
    assert not ForceCurve(story_pair, 0.98 * w_min).bound_state(1e-8).bound
    near = ForceCurve(story_pair, 0.98 * w_max).bound_state(1e-8)
    assert near.bound and near.r_eq < 1.05 * story_pair.contact_distance
    assert not ForceCurve(story_pair, 1.02 * w_max).bound_state(1e-8).bound


def test_small_floators_follow_eq6_18_exponent(story_pair):
    # Eq. 6.18 (and Fig. 5.26's fit, b = -0.326): omega ~ m^-1/3 for similar floators at the same
    # distance. It neglects the lateral circle (beta ~ 1/omega^2), which vanishes for small, fast
    # floators: there the solved exponent must approach -1/3.
    speeds = []
    for factor in (0.5e-3, 2e-3):
        pair = replace(story_pair, floator=scaled_floator(story_pair.floator, factor))
        speeds.append(speed_for_distance(pair, 0.012, STORY_OMEGA))
    exponent = math.log(speeds[1] / speeds[0]) / math.log(4.0)
    assert exponent == pytest.approx(-1 / 3, abs=0.01)
