"""One range syntax (labkit.ranges) for --set, --map, --ratios and the confirmation above a
documented size (issue 18, item 4)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.cli import main
from labkit.ranges import RangeError, parse_range


def test_step_and_count_are_spelt_differently() -> None:
    assert parse_range("6000:10000:step=2000") == [6000, 8000, 10000]
    assert parse_range("2:8:n=4") == [2, 4, 6, 8]
    assert parse_range("10000:6000:step=-2000") == [10000, 8000, 6000]
    assert parse_range("5:5:n=1") == [5]
    assert parse_range("1, 2,3") == [1, 2, 3] and parse_range("7") == [7]


def test_old_bare_spelling_is_a_step_in_set_and_refused_elsewhere() -> None:
    assert parse_range("6000:10000:2000", bare="step") == [6000, 8000, 10000]
    with pytest.raises(RangeError, match=r"ambiguous: write 2:8:n=7 for 7 values or 2:8:step=7"):
        parse_range("2:8:7", bare="error")


@pytest.mark.parametrize(("text", "reason"), [
    ("1:2", "start:stop:step=S or start:stop:n=N"), ("1:2:k=3", "third part is step=S or n=N"),
    ("1:2:n=0", "whole number >= 1"), ("1:2:n=2.5", "whole number >= 1"),
    ("1:0:step=1", "does not go"), ("1:2:step=0", "does not go"), ("0:1e9:step=1", "more than the limit"),
    ("1:nan:n=3", "not a finite number"), ("a,b", "not a number"), ("", "no values"),
])
def test_bad_ranges_say_why(text: str, reason: str) -> None:
    with pytest.raises(RangeError, match=reason):
        parse_range(text, bare="step")


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="0123456789.:,;-+eEnaifstp= ", max_size=30), st.sampled_from(["step", "error"]))
def test_any_text_gives_bounded_finite_values_or_one_range_error(text: str, bare: str) -> None:
    try:
        values = parse_range(text, bare=bare, limit=1000)  # type: ignore[arg-type]
    except RangeError as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    assert 1 <= len(values) <= 1000
    assert all(math.isfinite(v) for v in values)


@given(st.integers(-10_000, 10_000), st.integers(1, 500), st.integers(1, 200))
def test_count_ranges_have_n_values_from_start_to_stop(start: int, span: int, n: int) -> None:
    values = parse_range(f"{start}:{start + span}:n={n}")
    assert len(values) == n and values[0] == start
    if n > 1:
        assert math.isclose(values[-1], start + span, rel_tol=1e-12, abs_tol=1e-9)


def test_a_big_run_plan_is_refused_without_a_terminal(capsys, tmp_path) -> None:
    # 6000:20000:14 meant as "14 speeds" is a step of 14 RPM: 1001 steps
    code = main(["run", "emulated-fig525", "speed-sweep", "--set", "speeds_rpm=6000:20000:14",
                 "--sessions", str(tmp_path), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err == ("labkit run: 1001 measurement steps is more than 200; check the range "
                   "(a:b:step=S or a:b:n=N) and add --yes to go ahead (no terminal to ask on)")
    assert not any(tmp_path.iterdir())  # nothing started


def test_a_big_map_is_refused_without_a_terminal(capsys) -> None:
    code = main(["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm", "--no-verify",
                 "--map", "tilt_deg=2:8:n=30", "speed_rpm=10000:40000:n=30"])
    assert code == 2
    assert "900 map points is more than 500" in capsys.readouterr().err


def test_the_old_map_spelling_names_the_new_one(capsys) -> None:
    code = main(["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm", "--no-verify",
                 "--map", "speed_rpm=10000:40000:15000"])
    assert code == 2
    assert "write 10000:40000:n=15000 for 15000 values or 10000:40000:step=15000" in capsys.readouterr().err


def test_a_big_sweep_is_refused_without_a_terminal(capsys) -> None:
    assert main(["sweep", "table5.3", "--ratios", "0:0.6:n=1000", "--no-progress"]) == 2
    assert "11000 sweep points is more than 5000" in capsys.readouterr().err


@pytest.mark.parametrize(("answer", "goes_ahead"), [(b"y\n", True), (b"yes\n", True), (b"\n", False),
                                                    (b"n\n", False)])
def test_on_a_terminal_the_question_is_asked(answer: bytes, goes_ahead: bool, monkeypatch, capsys) -> None:
    """A real pseudo-terminal as stdin: the answer typed decides."""
    import os
    import pty

    from labkit.cli.confirm import confirm_size
    from labkit.errors import LabkitError

    master, slave = pty.openpty()
    with os.fdopen(slave, "r", encoding="utf-8") as terminal:
        try:
            monkeypatch.setattr("sys.stdin", terminal)
            os.write(master, answer)
            if goes_ahead:
                confirm_size(900, 500, "map points", yes=False, command="predict")
            else:
                with pytest.raises(LabkitError, match="not confirmed: 900 map points; nothing was started"):
                    confirm_size(900, 500, "map points", yes=False, command="predict")
        finally:
            os.close(master)
    assert "900 map points (more than 500). Go ahead? [y/N]" in capsys.readouterr().err


def test_yes_skips_the_question_and_small_plans_are_not_asked() -> None:
    from labkit.cli.confirm import confirm_size

    confirm_size(10_000, 500, "map points", yes=True, command="predict")  # no terminal needed
    confirm_size(500, 500, "map points", yes=False, command="predict")
