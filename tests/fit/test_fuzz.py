"""Fuzzing: any CSV text or any numbers end in a table, a fit, or a LabkitError — never a crash."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from labkit.errors import LabkitError
from labkit.fit import FitOptions, fit_table, load_table
from labkit.fit.models import fit_pfr_force, fit_power_law, fit_spin_critical

cells = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.text(max_size=6),
                  st.just(""), st.just("nan"))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.lists(cells, min_size=1, max_size=4), min_size=0, max_size=8),
       st.sampled_from(["power-law", "spin-critical", "pfr-force", "cone-angle", "mbs-force"]))
def test_any_csv_gives_a_table_or_a_labkit_error(rows, model):
    header = "speed_rpm,force_g,rotor_rad_s,spin_rad_s"
    text = header + "\n" + "\n".join(",".join(r) for r in rows)
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "fuzz.csv"
        path.write_text(text)
        try:
            fit_table(load_table(path), model, FitOptions(inertia=1e-7))
        except LabkitError:
            pass


finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)


@settings(max_examples=150, deadline=None, phases=[Phase.explicit, Phase.reuse, Phase.generate, Phase.shrink])
@given(st.lists(st.tuples(finite, finite), min_size=0, max_size=10))
def test_any_numbers_give_a_fit_or_a_fit_error(pairs):
    x = np.array([p[0] for p in pairs], dtype=float)
    y = np.array([p[1] for p in pairs], dtype=float)
    for fit in (lambda: fit_power_law(x, y), lambda: fit_pfr_force(x, y, inertia=1e-7),
                lambda: fit_spin_critical(x, y)):
        try:
            res = fit()
        except LabkitError:
            continue
        for p in res.params.values():
            assert p.ci95[0] <= p.value <= p.ci95[1] or not np.isfinite(p.stderr)
