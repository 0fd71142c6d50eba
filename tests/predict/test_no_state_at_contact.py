"""A pair whose co-rotating steady state does not exist at contact still gets its bound state
(it used to end in a traceback: brentq on a NaN at the contact distance)."""

from __future__ import annotations

import math

from labkit.predict.magnets import parse_magnet_spec
from labkit.predict.pair import ForceCurve, Pair


def test_bound_state_search_starts_where_the_steady_state_exists():
    pair = Pair(parse_magnet_spec("cylinder:6x3mm"), parse_magnet_spec("block:8.57x8.57x3.00mm"),
                math.radians(10.735))
    curve = ForceCurve(pair, 12809 / 60 * 2 * math.pi)
    assert math.isnan(curve(pair.contact_distance))  # the premise: no steady state at contact
    bound = curve.bound_state()
    assert bound.bound, bound.reason
    # net force zero at the equilibrium, and stiff (S > 0) there
    assert abs(curve(bound.r_eq) + pair.load) < 1e-6 * abs(pair.load)
    assert bound.stiffness > 0 and pair.contact_distance < bound.r_eq < bound.r_limit
