"""--set parsing and the progress bar sink."""

import io

import pytest

from labkit import documents as doc
from labkit.protocols import ProgressSink
from labkit.protocols.params import ParamError, parse_number_list, resolve_params


def test_ranges_are_inclusive_and_lists_are_kept_in_order():
    assert parse_number_list("s", "6000:10000:2000") == [6000, 8000, 10000]
    assert parse_number_list("s", "10000:6000:-2000") == [10000, 8000, 6000]
    assert parse_number_list("s", "9000,6000,12000") == [9000, 6000, 12000]


@pytest.mark.parametrize("text, problem", [("6000:7000", "start:stop:step"), ("6000:7000:-1", "does not go"),
                                           ("fast", "not a number")])
def test_bad_lists_say_what_is_wrong(text, problem):
    with pytest.raises(ParamError, match=problem):
        parse_number_list("speeds_rpm", text)


def test_values_take_the_type_of_the_default():
    defaults = {"n": 3, "x": 1.5, "flag": False, "mode": "each", "speeds": [1.0]}
    got = resolve_params(defaults, ["n=4", "x=2", "flag=yes", "mode=start", "speeds=1,2"], "p")
    assert got == {"n": 4, "x": 2.0, "flag": True, "mode": "start", "speeds": [1.0, 2.0]}
    with pytest.raises(ParamError, match="--set n: 'four' is not an integer"):
        resolve_params(defaults, ["n=four"])
    with pytest.raises(ParamError, match="expected key=value"):
        resolve_params(defaults, ["n"])


def test_progress_bar_shows_step_k_of_n_and_the_settle_state():
    from rich.console import Console

    out = io.StringIO()
    sink = ProgressSink(Console(file=out, force_terminal=True, width=120))
    sink.on_event(doc.RunStart(t=0.0, protocol="speed-sweep", params={}, rig="r", n_steps=4))
    sink.on_event(doc.StepStart(t=1.0, index=1, n_steps=4, label="up 8000 RPM", targets_rad_s={}))
    sink.on_event(doc.Settled(t=2.0, index=1, settle_time_s=2.5))
    sink.on_event(doc.PointDone(t=3.0, index=1, point={}))
    sink.on_event(doc.RunStop(t=4.0, status="completed"))
    text = out.getvalue()
    assert "2/4" in text and "settled in 2.5 s" in text and "speed-sweep" in text
