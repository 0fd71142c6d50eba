"""Ill-conditioned and bad data end with a clear message, never a silent fit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.errors import FitError
from labkit.fit.models import (
    critical_spin,
    fit_cone_angle,
    fit_mbs_force,
    fit_pfr_force,
    fit_power_law,
    fit_spin_critical,
    mbs_force,
    pfr_force,
)

rng = np.random.default_rng(7)


def test_speed_range_too_narrow_to_fix_exponent_warns():
    x = np.linspace(10000, 10100, 8)                     # 1 % speed range
    y = 224e6 * x**-1.9 * np.exp(rng.normal(0, 0.02, x.size))
    res = fit_power_law(x, y, x_name="speed_rpm", y_name="force_g")
    assert any("b not identifiable" in w for w in res.warnings), res.warnings
    # and the interval says so: it is far wider than the exponent itself
    lo, hi = res.params["b"].ci95
    assert hi - lo > 2 * abs(res.params["b"].value)


def test_wide_speed_range_gives_no_warning():
    x = np.geomspace(6000, 20000, 8)
    res = fit_power_law(x, 224e6 * x**-1.9 * np.exp(rng.normal(0, 0.02, x.size)))
    assert res.warnings == ()


def test_pole_on_the_data_is_refused():
    """I omega^2 close to tau_S at the lowest speed: tau_S runs into its bound."""
    inertia = 1e-7
    omega = np.linspace(600, 900, 10)
    tau_S = inertia * 600.0**2 * 0.99995                 # pole 0.005 % below the lowest point
    f = pfr_force(omega, 2e-4, inertia, tau_S) * np.exp(rng.normal(0, 0.01, omega.size))
    with pytest.raises(FitError, match="tau_S sits at its bound"):
        fit_pfr_force(omega, f, inertia=inertia)


def test_near_pole_warns():
    inertia = 1e-7
    omega = np.linspace(600, 1500, 12)
    tau_S = inertia * 600.0**2 * 0.98
    f = pfr_force(omega, 2e-4, inertia, tau_S) * np.exp(rng.normal(0, 0.005, omega.size))
    res = fit_pfr_force(omega, f, inertia=inertia)
    assert any("near the pole" in w or "dominated by points near the pole" in w for w in res.warnings)


@pytest.mark.parametrize("fit", [
    lambda x, y: fit_power_law(x, y),
    lambda x, y: fit_pfr_force(x, y, inertia=1e-7),
])
def test_all_points_equal_is_refused(fit):
    x = np.full(6, 800.0)
    with pytest.raises(FitError, match="are equal"):
        fit(x, np.full(6, 0.1))
    with pytest.raises(FitError, match="are equal"):
        fit(np.linspace(700, 900, 6), np.full(6, 0.1))


def test_nan_force_is_refused_naming_the_row():
    x = np.linspace(6000, 20000, 6)
    y = 224e6 * x**-1.9
    y[3] = math.nan
    with pytest.raises(FitError, match=r"'force_g'.*row 4"):
        fit_power_law(x, y, y_name="force_g")


def test_negative_force_is_refused():
    x = np.linspace(6000, 20000, 6)
    y = 224e6 * x**-1.9
    y[1] = -0.3
    with pytest.raises(FitError, match=r"must be positive.*row 2.*-0.3"):
        fit_power_law(x, y, y_name="force_g")
    with pytest.raises(FitError, match="must be positive"):
        fit_pfr_force(x, y, inertia=1e-7)


@pytest.mark.parametrize("n", [0, 1, 2])
def test_fewer_points_than_parameters(n):
    x = np.array([6000.0, 9000.0])[:n]
    with pytest.raises(FitError, match=f"{n} point\\(s\\) for 2 fitted parameter"):
        fit_power_law(x, 224e6 * x**-1.9)
    with pytest.raises(FitError, match=f"{n} point\\(s\\) for 2 fitted parameter"):
        fit_pfr_force(x, 1 / (1e-7 * x**2), inertia=1e-7)
    with pytest.raises(FitError, match=f"{n} point\\(s\\) for 4 fitted parameter"):
        fit_mbs_force(x * 1e-5, 1e-3 * x)


@pytest.mark.parametrize("seed", range(4))
def test_free_four_parameter_mbs_fit_is_flagged_ill_conditioned(seed):
    """Either a fit with an ill-conditioning warning or a refusal that says what to do."""
    r = np.linspace(0.018, 0.032, 20)
    c, b, d = 1e-7, 7.5, 3.8
    a = c * 0.0245 ** (b - d)
    f = mbs_force(r, a, b, c, d)
    noisy = f + np.random.default_rng(seed).normal(0, 0.05 * np.abs(f).max(), r.size)
    try:
        res = fit_mbs_force(r, noisy)
    except FitError as exc:
        assert "not identifiable" in str(exc) and "--fix d=3.8" in str(exc)
        return
    assert any("ill-conditioned" in w or "correlated" in w or "not identifiable" in w
               for w in res.warnings), res.warnings
    fixed = fit_mbs_force(r, f + rng.normal(0, 0.002 * np.abs(f).max(), r.size), fixed={"d": 3.8})
    assert fixed.params["d"].fixed
    assert fixed.params["b"].covers(7.5) or abs(fixed.params["b"].value - 7.5) < 0.1


def test_spin_critical_without_curvature_cannot_fit_omega_c():
    omega = np.linspace(620, 1100, 10)
    v = critical_spin(omega, 4.7e5, math.inf) + rng.normal(0, 15, omega.size)   # Eq. 5.69 exactly
    res = fit_spin_critical(omega, v, omega_c="fit")
    assert any("omega_c not determined" in w or "omega_c not identifiable" in w for w in res.warnings), \
        res.warnings


def test_cone_angle_zero_is_refused():
    omega = np.linspace(150, 500, 6)
    phi = np.full(6, 0.1)
    phi[2] = 0.0
    with pytest.raises(FitError, match="cone angle of exactly 0"):
        fit_cone_angle(omega, phi, inertia=1e-7)


def test_bad_inertia_is_refused():
    omega = np.linspace(600, 900, 6)
    with pytest.raises(FitError, match="moment of inertia"):
        fit_pfr_force(omega, 1 / omega**2, inertia=-1.0)
