"""The ICP engine of the laser fit (labkit/vision/laser/icp.py) against references written here
from the definitions: phasors against ``np.exp``, the complex-form normal equations against a
least-squares solve of the real rows built point by point, and the whole ICP recovering a curve
it was given."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.vision.laser.icp import TANGENTIAL_WEIGHT, FitRows, icp_rows, solve_point_to_line
from labkit.vision.shared.curves import phasors


@settings(max_examples=60, deadline=None)
@given(k=st.integers(-9, 9), seed=st.integers(0, 2**31 - 1), scale=st.sampled_from([1.0, 7.0, 100.0]))
def test_phasors_agree_with_complex_exp(k: int, seed: int, scale: float) -> None:
    t = np.random.default_rng(seed).uniform(-scale, scale, 300)
    e1, ek = phasors(t, k)
    assert np.max(np.abs(e1 - np.exp(1j * t))) < 1e-15
    # repeated squaring: a few units in the last place per squaring
    assert np.max(np.abs(ek - np.exp(1j * k * t))) < 1e-14 * max(1, abs(k))


def test_phasors_take_one_k_per_row() -> None:
    rng = np.random.default_rng(3)
    t = rng.uniform(0, 2 * math.pi, (7, 50))
    k = np.array([[-1], [2], [3], [-1], [-4], [7], [2]])
    e1, ek = phasors(t, k)
    assert np.max(np.abs(ek - np.exp(1j * k * t))) < 1e-13
    assert np.max(np.abs(e1 - np.exp(1j * t))) < 1e-15
    with pytest.raises(ValueError, match="one per row"):
        phasors(t, np.array([2, 3]))


def _reference_solve(z, sw, tau, rows, t, fit_drift):
    """The least-squares problem of the docstring, one real row per point and direction."""
    out = []
    for i in range(len(rows.k)):
        k, a, b = int(rows.k[i]), rows.a[i], rows.b[i]
        m_rows, rhs = [], []
        for p in range(z.shape[1]):
            e1, ek = np.exp(1j * t[i, p]), np.exp(1j * k * t[i, p])
            tangent = 1j * (a * e1 + k * b * ek)
            tangent /= max(abs(tangent), 1e-12)
            basis = [1.0, e1, ek] + ([tau[p]] if fit_drift else [])
            for direction, weight in ((1j * tangent, 1.0), (tangent, TANGENTIAL_WEIGHT)):
                q = [np.conj(direction) * g for g in basis]
                m_rows.append([v for qj in q for v in (qj.real, -qj.imag)])
                rhs.append((np.conj(direction) * z[0, p]).real)
                m_rows[-1] = [v * sw[p] * weight for v in m_rows[-1]]
                rhs[-1] *= sw[p] * weight
        x = np.linalg.lstsq(np.array(m_rows), np.array(rhs), rcond=None)[0]
        out.append(x[0::2] + 1j * x[1::2])
    return np.array(out)


@pytest.mark.parametrize("fit_drift", [True, False])
def test_normal_equations_match_the_real_least_squares(fit_drift: bool) -> None:
    rng = np.random.default_rng(11)
    n, s = 80, 5
    rows = FitRows(np.array([-1, 3, -2, 4, -1]), 300 + rng.normal(0, 5, s) + 1j * rng.normal(200, 5, s),
                   (90 + rng.normal(0, 3, s)) * np.exp(1j * rng.uniform(0, 6, s)),
                   25 * np.exp(1j * rng.uniform(0, 6, s)), np.zeros(s, complex))
    t = rng.uniform(0, 2 * math.pi, (s, n))
    z = (300 + 200j + 95 * np.exp(1j * rng.uniform(0, 6, n)) + rng.normal(0, 1, n))[None, :]
    sw, tau = np.sqrt(rng.uniform(0.2, 3, n)), rng.uniform(-4, 4, n)
    got = solve_point_to_line(z, sw, tau, rows, phasors(t, rows.k[:, None]), fit_drift)
    want = _reference_solve(z, sw, tau, rows, t, fit_drift)
    assert got.shape == want.shape == (s, 4 if fit_drift else 3)
    assert np.max(np.abs(got - want)) < 1e-8 * np.max(np.abs(want))


@pytest.mark.parametrize("k", [-1, 4, -2])
def test_icp_recovers_a_drifting_curve(k: int) -> None:
    c, a, b, v = 640 + 360j, 150 * np.exp(0.4j), (40 if k != -1 else 60) * np.exp(-1.1j), 3 - 2j
    t = np.linspace(0, 2 * math.pi, 900, endpoint=False)
    tau = np.linspace(-5, 5, len(t))
    z = c + a * np.exp(1j * t) + b * np.exp(1j * k * t) + v * tau
    start = FitRows(np.array([k]), np.array([c + 4 - 3j]), np.array([a * 1.05 * np.exp(0.05j)]),
                    np.array([b * 0.9]), np.array([0j]))
    rows, rms = icp_rows(z, np.ones(len(z)), tau, start, 40, True, np.array([360 * abs(k)]))
    # the fit stops once a step moves c, A, B by < 1e-3 px (checked every sixth step): it ends
    # within a few hundredths of a pixel of the curve, not at round-off
    assert rms[0] < 0.05
    # a shift of the curve parameter by p multiplies A by e^{ip} and B by e^{ikp}: the same curve
    got_a, got_b = rows.a[0], rows.b[0]
    for got, want in ((rows.c[0], c), (rows.v[0], v), (abs(got_a), abs(a)), (abs(got_b), abs(b))):
        assert abs(got - want) < 0.05
    turn = np.angle((got_b / got_a**k) / (b / a**k))  # the relative phase of the two terms
    assert abs(turn) < 1e-3
