"""Fits recover known parameters within their reported uncertainty at the stated coverage.

Each test draws seeded synthetic data from the model with known parameters and Gaussian
noise, fits, and counts how often the 95 % interval covers the truth. With 300 trials the
binomial standard deviation of the coverage is 1.3 %, so [0.91, 0.985] is a ~3 sigma band.
"""

from __future__ import annotations

import numpy as np
import pytest

from labkit.fit.models import (
    cone_angle,
    critical_spin,
    fit_cone_angle,
    fit_mbs_distance,
    fit_pfr_force,
    fit_power_law,
    fit_spin_critical,
    pfr_force,
)

TRIALS = 300
LOW, HIGH = 0.91, 0.985


def coverage(trial, truth: dict[str, float], seed: int) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    hits = {k: 0 for k in truth}
    for _ in range(TRIALS):
        res = trial(rng)
        for k, v in truth.items():
            hits[k] += res.params[k].covers(v)
    return {k: h / TRIALS for k, h in hits.items()}


def assert_coverage(cov: dict[str, float]) -> None:
    for k, c in cov.items():
        assert LOW <= c <= HIGH, f"{k}: 95 % interval covered the truth in {c:.1%} of trials"


def test_power_law_fig525_coverage():
    x = np.linspace(6000, 20000, 12)          # RPM, as Fig. 5.25
    truth = {"a": 224e6, "b": -1.9}

    def trial(rng):
        y = 224e6 * x**-1.9 * np.exp(rng.normal(0, 0.03, x.size))
        return fit_power_law(x, y)

    assert_coverage(coverage(trial, truth, seed=1))


def test_pfr_force_coverage():
    inertia, K, tau_S = 1e-7, 2e-4, 0.01      # I omega^2 from 0.036 to 0.4 N m
    omega = np.linspace(600, 2000, 14)

    def trial(rng):
        f = pfr_force(omega, K, inertia, tau_S) * np.exp(rng.normal(0, 0.02, omega.size))
        return fit_pfr_force(omega, f, inertia=inertia)

    assert_coverage(coverage(trial, {"K": K, "tau_S": tau_S}, seed=2))


@pytest.mark.parametrize("omega_c", [3000.0, "fit"])
def test_spin_critical_coverage(omega_c):
    C = 4.7e5
    omega = np.linspace(620, 1100, 10)

    def trial(rng):
        v = critical_spin(omega, C, 3000.0) + rng.normal(0, 15.0, omega.size)
        return fit_spin_critical(omega, v, omega_c=omega_c)

    truth = {"C": C} if omega_c != "fit" else {"C": C, "omega_c": 3000.0}
    cov = coverage(trial, truth, seed=3)
    if omega_c == "fit":
        # omega_c = C/D is a ratio: its delta-method interval is approximate
        assert LOW <= cov["C"] <= HIGH
        assert 0.88 <= cov["omega_c"] <= 0.99, cov
    else:
        assert_coverage(cov)


@pytest.mark.parametrize("spin_ratio", [0.0, 0.3])
def test_cone_angle_coverage(spin_ratio):
    inertia, tau_C, tau_S = 1e-7, 1e-3, 1e-4
    omega = np.linspace(150, 500, 10)
    spin = spin_ratio * omega

    def trial(rng):
        phi = cone_angle(omega, tau_C, tau_S, inertia, spin=spin) + rng.normal(0, 0.003, omega.size)
        return fit_cone_angle(omega, phi, inertia=inertia, spin=spin)

    assert_coverage(coverage(trial, {"tau_C": tau_C, "tau_S": tau_S}, seed=4))


def test_mbs_distance_coverage_and_b_minus_d():
    omega = np.linspace(500, 1500, 10)
    r_true = 0.6 * omega ** -0.5                  # b - d = 4 (Eq. 6.13 rounded as in the paper)

    def trial(rng):
        return fit_mbs_distance(omega, r_true * np.exp(rng.normal(0, 0.01, omega.size)))

    assert_coverage(coverage(trial, {"A": 0.6, "p": -0.5, "b_minus_d": 4.0}, seed=5))


def test_recovered_values_are_close_to_truth_with_small_noise():
    x = np.geomspace(6000, 20000, 10)
    res = fit_power_law(x, 224e6 * x**-1.9 * np.exp(np.random.default_rng(0).normal(0, 1e-4, 10)))
    assert res.params["b"].value == pytest.approx(-1.9, abs=1e-3)
    assert res.params["a"].value == pytest.approx(224e6, rel=0.01)
    assert res.warnings == ()


def test_fitted_curves_are_the_closed_forms_of_labkit_model():
    """The fits' internal, rescaled models agree with labkit.model's closed forms
    (Eq. 5.24/5.68, 6.37, 5.85) at the fitted parameters."""
    from labkit.fit.models import fit_mbs_force
    from labkit.model.cone import cone_angle as eq524
    from labkit.model.cone import cone_angle_spin as eq568
    from labkit.model.mbs import mbs_force as eq585
    from labkit.model.mbs import spin_for_speed as eq637
    rng = np.random.default_rng(9)
    omega = np.linspace(150, 500, 10)
    phi = eq524(1e-3, 1e-4, 1e-7, omega) + rng.normal(0, 0.002, omega.size)
    res = fit_cone_angle(omega, phi, inertia=1e-7)
    tc, ts = res.params["tau_C"].value, res.params["tau_S"].value
    assert np.allclose(res.predict(omega), eq524(tc, ts, 1e-7, omega), rtol=1e-9)
    spin = 0.4 * omega
    phi = eq568(1e-3, 1e-4, 1e-7, omega, spin / omega - 1) + rng.normal(0, 0.002, omega.size)
    res = fit_cone_angle(omega, phi, inertia=1e-7, spin=spin)
    fitted = eq568(res.params["tau_C"].value, res.params["tau_S"].value, 1e-7, omega, spin / omega - 1)
    assert np.allclose(phi - fitted, res.residuals, atol=1e-9)
    w = np.linspace(620, 1100, 9)
    res = fit_spin_critical(w, eq637(w, 4.7e5) + rng.normal(0, 10, w.size))
    assert np.allclose(res.predict(w), eq637(w, res.params["C"].value, 3000.0), rtol=1e-9)
    r = np.linspace(0.018, 0.032, 15)
    f = eq585(r, 1e-7 * 0.0245**3.7, 7.5, 1e-7, 3.8)
    res = fit_mbs_force(r, f + rng.normal(0, 0.002 * np.abs(f).max(), r.size), fixed={"d": 3.8})
    p = {k: res.params[k].value for k in "abcd"}
    assert np.allclose(res.predict(r), eq585(r, **p), rtol=1e-7, atol=1e-12)
