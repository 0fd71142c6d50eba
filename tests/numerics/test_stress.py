"""The stress-case runner returns one verdict per case S1-S11, each with its criterion."""

from __future__ import annotations

import json

from labkit.numerics.stress import CASES, NAMES, case_id, run_stress_cases


def test_every_stress_case_returns_a_verdict():
    verdicts = run_stress_cases(level="smoke")
    assert [v.id for v in verdicts] == list(CASES) == [f"S{i}" for i in range(1, 12)]
    assert [v.name for v in verdicts] == [NAMES[f"S{i}"] for i in range(1, 12)]
    assert len(set(NAMES.values())) == 11 and all(v.to_json()["name"] == v.name for v in verdicts)
    for v in verdicts:
        assert isinstance(v.met, bool)
        assert v.criterion and v.measured, v.id
        json.dumps(v.to_json())  # every verdict is JSON-ready
    by_id = {v.id: v for v in verdicts}
    # cases whose outcome has an independent reason to hold:
    assert by_id["S8"].measured["status"] == "contact"  # released at 1 m/s towards the rotator
    assert by_id["S9"].measured["status"] == "escape"  # released at 2 m/s away from it
    assert by_id["S3"].measured["sign_flip_reproduced"]  # Eq. 5.24 changes sign at tau_S = I w^2
    assert by_id["S2"].met  # the same ODE in other units (NUMERICS.md 3.1)


def test_cases_are_found_by_name_or_s_number():
    assert case_id("two-body-bound-state") == case_id("S7") == case_id("s7") == "S7"
    assert case_id("S12") is None and case_id("no-such-case") is None
    verdicts = run_stress_cases(level="smoke", only=["contact-event", "S9"])
    assert [(v.id, v.name) for v in verdicts] == [("S8", "contact-event"), ("S9", "escape-event")]
