"""All 36 rows of Table 5.3: the co-rotating linear analysis gives Eq. 5.46's verdict everywhere,
and the paper's verdict except in four rows whose growth rates explain the difference."""

import pytest

from labkit.model import conical_dynamics as cd
from labkit.model.stability import criterion_holds
from labkit.reproduce.paper_data import TABLE_5_3

# row -> growth rate (1/s) of the linear analysis where the paper says "stable" (lambda = 0):
# these rows sit 1-3 % below the Eq. 5.46 minimum; slow growth from the paper's small initial
# kick (row 15: 0.004 rad after the paper's ~0.5 s) was read as a stable cone.
PAPER_STABLE_BUT_GROWING = {7: 2.61, 15: 6.22, 22: 6.71}
# row 12 (tau_S/tau_C = 0.55, far above the minimum 0.221): the paper reports a growing
# oscillation; the linear analysis, Eq. 5.46 and a 3 s time-domain run all find it stable.
PAPER_UNSTABLE_BUT_STABLE = {12}


@pytest.mark.parametrize("row", TABLE_5_3, ids=lambda r: f"row{r[0]}")
def test_linear_verdict(row):
    no, i_a, i_r, omega, tau_c, ratio, *_rest = row
    tilted = row[10]
    body = cd.RotatingFieldBody.from_si(tau_c, ratio * tau_c, i_a, i_r, omega)
    rate = cd.growth_rate(body) * omega
    stable = rate < 1e-6 * omega
    assert stable == bool(criterion_holds(tau_c, ratio * tau_c, i_r, omega))
    if no in PAPER_STABLE_BUT_GROWING:
        assert not tilted and rate == pytest.approx(PAPER_STABLE_BUT_GROWING[no], rel=0.01)
    elif no in PAPER_UNSTABLE_BUT_STABLE:
        assert tilted and stable
    else:
        assert stable is (not tilted)
