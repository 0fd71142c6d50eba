"""Quick fits recover known parameters from synthetic data."""

import numpy as np
import pytest

from labkit.protocols.quickfit import fit_spin_critical_c, quick_fit_power_law


def test_power_law_recovers_the_paper_fit_from_noisy_data():
    rng = np.random.default_rng(4)
    x = np.arange(6000, 20001, 1000.0)
    y = 224e6 * x**-1.9 * (1 + 0.01 * rng.standard_normal(len(x)))
    fit = quick_fit_power_law(list(x), list(y), sigma=list(0.01 * y))
    b = fit["params"]["b"]
    assert b["value"] == pytest.approx(-1.9, abs=0.02)
    assert 0 < b["stderr"] < 0.05
    assert fit["params"]["a"]["value"] == pytest.approx(224e6, rel=0.3)


def test_power_law_refuses_too_few_points():
    with pytest.raises(ValueError, match=">= 3"):
        quick_fit_power_law([1000, 2000], [1.0, 0.5])


def test_eq637_c_from_the_paper_series_1():
    # Fig. 6.18 caption, series 1; the paper quotes C = 4.7e5 for it
    v = [0, 136, 266, 340, 417, 498, 574, 712, 817]
    w = [625, 670, 733, 782, 827, 859, 932, 1022, 1100]
    fit = fit_spin_critical_c(w, v)
    assert fit["params"]["C"]["value"] == pytest.approx(4.7e5, rel=0.06)


def test_eq637_c_exact_on_pairs_on_the_curve():
    c, w = 6.63e5, np.array([700.0, 800.0, 900.0])
    v = w - c * (1 - w / 3000) / w
    fit = fit_spin_critical_c(list(w), list(v))
    assert fit["params"]["C"]["value"] == pytest.approx(c, rel=1e-9)



def test_run_labels_its_quick_fit_as_another_least_squares_than_labkit_fit(tmp_path, capsys):
    """`labkit run` prints which residuals its quick fit minimises and which `labkit fit` does
    (the digits differ on purpose: docs/reference/fitting.md)."""
    from labkit.cli import main

    code = main(["run", "rigs/emulated-fig618.toml", "spin-critical", "--sessions", str(tmp_path),
                 "--no-progress", "--set", "start_rpm=6600", "--set", "stop_rpm=8000",
                 "--set", "step_pct=15"])
    out = capsys.readouterr().out
    assert code == 0
    assert ("quick fit (eq6.37, least squares in w^2 - v w; labkit fit --model spin-critical fits the "
            "spin v, see docs/reference/fitting.md): C = ") in out
