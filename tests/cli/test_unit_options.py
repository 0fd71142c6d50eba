"""Command-line options that carry units or counts (issue 27): a value typed in the wrong unit,
a non-finite or out-of-range number is refused with its reason, exit 2, no traceback; a result
the inputs make implausible says so; a speed far too low is refused at once; Ctrl-C names only
what the command stops; a closed stdout pipe ends quietly."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.cli import main
from labkit.cli.numbers import check_number
from labkit.cli.synth import strobe_coverage_problem

REPO = Path(__file__).resolve().parents[2]


def cli(argv: list, capsys) -> tuple[int, str, str]:
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse refuses an option value with exit 2
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def laser_clip(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("laser") / "ring.mp4"
    assert main(["synth", "laser", str(path), "--frames", "20", "--size", "320x240"]) == 0
    return path


@pytest.mark.parametrize("argv, words", [
    (["--screen-distance-mm", "0.5", "--mm-per-px", "0.21"],
     ["--screen-distance-mm: 0.5 mm from the magnet to the screen", "looks like metres: did you mean "
      "--screen-distance-mm 500?"]),
    (["--screen-distance-mm", "500", "--mm-per-px", "0.00021"],
     ["--mm-per-px: 0.00021 mm per pixel", "looks like metres per pixel: did you mean 0.21?"]),
    (["--chunk-s", "inf"], ["--chunk-s: must be a finite number > 0 and <= 3600, got inf"]),
    (["--chunk-s", "nan"], ["--chunk-s: must be a finite number > 0 and <= 3600, got nan"]),
])
def test_analyse_laser_refuses_options_in_the_wrong_unit_or_not_finite(laser_clip, capsys, argv, words):
    code, out, err = cli(["analyse", "laser", laser_clip, *argv], capsys)
    assert code == 2 and out == "" and "Traceback" not in err
    for word in words:
        assert word in err, (word, err)


def test_a_tilt_beyond_the_screen_geometry_is_doubtful_with_the_reason(laser_clip, tmp_path, capsys):
    out_json = tmp_path / "r.json"
    code, out, err = cli(["analyse", "laser", laser_clip, "--screen-distance-mm", "12", "--mm-per-px", "0.21",
                          "--json", out_json], capsys)
    assert code == 0, err
    result = json.loads(out_json.read_text())
    quality = result["quality"]
    assert quality["verdict"] == "doubtful" and quality["checks"]["tilt_geometry"] == "doubtful"
    semi_mm = result["pattern"]["semi_axes_px"][0] * 0.21
    assert semi_mm > 12
    reason = next(r for r in quality["reasons"] if "screen distance" in r)
    assert f"({semi_mm:.3g} mm) is longer than the screen distance (12 mm)" in reason
    assert "result doubtful" in out and "longer than the screen distance" in out
    # the same clip seen from a plausible distance keeps its verdict
    code, out, err = cli(["analyse", "laser", laser_clip, "--screen-distance-mm", "500",
                          "--mm-per-px", "0.21", "--json", out_json], capsys)
    assert code == 0 and "tilt_geometry" not in json.loads(out_json.read_text())["quality"]["checks"]


def test_screen_distance_without_scale_says_why_no_tilt_is_printed(laser_clip, capsys):
    code, out, err = cli(["analyse", "laser", laser_clip, "--screen-distance-mm", "500"], capsys)
    assert code == 0
    assert "no tilt will be printed: --screen-distance-mm without --mm-per-px" in err
    assert "tilt amplitude" not in out


def test_synth_strobe_refuses_an_apparent_frequency_of_zero(tmp_path, capsys):
    out_path = tmp_path / "still.mp4"
    code, out, err = cli(["synth", "strobe", out_path, "--strobe-hz", "240", "--rotor-hz", "240"], capsys)
    assert code == 2 and "Traceback" not in err
    assert "a still clip: --rotor-hz 240 is 1 x --strobe-hz 240: the apparent frequency is 0 Hz" in err
    assert not out_path.exists()


def test_synth_strobe_warns_when_the_frames_cover_too_little_of_the_cycle(tmp_path, capsys):
    # written (a clip to test poor coverage is a use), but not silently
    clip = tmp_path / "s.mp4"
    code, out, err = cli(["synth", "strobe", clip, "--strobe-hz", "240.5", "--rotor-hz", "240"], capsys)
    assert code == 0 and clip.exists()
    assert err.startswith(f"labkit synth: warning: {clip}: 48 frames at 240.5 Hz cover 0.1 of the "
                          "apparent cycle")
    assert "use --frames 482" in err
    code, out, err = cli(["analyse", "strobe", clip, "--rotor-hz", "240", "--strobe-hz", "240.5"], capsys)
    assert code == 1 and "the frames sample too little of the cycle" in err


def test_story_4_4_synth_strobe_defaults_make_a_clip_analyse_strobe_accepts(tmp_path, capsys):
    clip = tmp_path / "check.mp4"
    code, out, err = cli(["synth", "strobe", clip], capsys)
    assert code == 0, err
    truth = json.loads(clip.with_name("check.truth.json").read_text())
    code, out, err = cli(["analyse", "strobe", clip, "--json", tmp_path / "s.json"], capsys)
    assert code == 0, err
    result = json.loads((tmp_path / "s.json").read_text())
    assert result["quality"]["verdict"] == "ok", result["quality"]["reasons"]
    assert result["tilt_amplitude_rad"] == pytest.approx(truth["tilt_amplitude_rad"], abs=0.01)


def test_a_laser_clip_analysed_as_strobe_exits_non_zero(laser_clip, capsys):
    code, out, err = cli(["analyse", "strobe", laser_clip], capsys)
    assert code == 1 and "result failed" in err


@pytest.mark.parametrize("argv, words", [
    (["simulate", "conical_5_1", "--cycles", "-1"], ["--cycles: must be a finite number > 0, got -1"]),
    (["simulate", "conical_5_1", "--cycles", "nan"], ["--cycles: must be a finite number > 0, got nan"]),
    (["simulate", "conical_5_1", "--samples-per-period", "0"],
     ["--samples-per-period: must be a whole number >= 1", "got 0"]),
    (["fit", "nothing.csv", "--model", "pfr-force", "--bootstrap", "1000000000"],
     ["--bootstrap: must be a whole number >= 0 and <= 100000", "10 000 give the 95 % interval"]),
])
def test_counts_and_numbers_are_refused_before_any_work(capsys, argv, words):
    code, out, err = cli(argv, capsys)
    assert code == 2 and "Traceback" not in err, err
    for word in words:
        assert word in err, (word, err)


def test_predict_refuses_a_speed_far_too_low_at_once(capsys):
    start = time.monotonic()
    code, out, err = cli(["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm",
                          "--speed-rpm", "25"], capsys)
    assert time.monotonic() - start < 10
    assert code == 2 and out == ""
    assert err.startswith("labkit predict: no bound state at 25 rpm") and "did you mean 25000 rpm?" in err
    assert err.count("\n") == 1


def test_predict_refuses_a_speed_far_below_the_minimum_speed_quickly(capsys):
    start = time.monotonic()
    code, out, err = cli(["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm",
                          "--speed-rpm", "250", "--no-verify"], capsys)
    assert time.monotonic() - start < 10
    assert code == 2 and out == ""
    # the estimate against the minimum speed the full prediction finds (9382 rpm at 25000 rpm)
    assert err.startswith("labkit predict: no bound state at 250 rpm: the minimum speed is about 9")
    assert "Eq. 5.81" in err and err.count("\n") == 1
    # a speed a quarter of the minimum is predicted in full (no bound state, said in the table)
    code, out, err = cli(["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm",
                          "--speed-rpm", "2500", "--no-verify"], capsys)
    assert code == 0 and "no bound state" in out


def _labkit(*argv: str, **kw) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen([sys.executable, "-m", "labkit", *argv], env=env, stderr=subprocess.PIPE,
                            **kw)


def _ctrl_c_reaches_python() -> None:
    """In the child: SIGINT at its default, so Python installs its KeyboardInterrupt handler.
    A shell without job control starts background commands with SIGINT ignored (`.ci/run &`),
    and an ignored SIGINT is inherited: predict would never see this test's Ctrl-C."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_of_predict_does_not_speak_of_motors():
    # a prediction with a 200 000-cycle simulation check takes over 10 s: Ctrl-C lands mid-work
    # however late this process wakes from its sleep on a loaded machine
    proc = _labkit("predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm", "--speed-rpm",
                   "25000", "--verify-cycles", "200000", stdout=subprocess.DEVNULL,
                   preexec_fn=_ctrl_c_reaches_python)
    try:
        line = proc.stderr.readline().decode()
        assert "computing" in line
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        err = proc.stderr.read().decode()
        assert proc.wait(timeout=30) == 130
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert "labkit predict: interrupted" in err and "motor" not in err, err


def test_a_closed_stdout_pipe_ends_quietly():
    proc = _labkit("rig", "check", str(REPO / "rigs" / "emulated-fig525.toml"), stdout=subprocess.PIPE)
    proc.stdout.close()  # the reader (head) is gone before the command prints
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 141
    assert "Traceback" not in err and "BrokenPipeError" not in err, err


@settings(max_examples=300, deadline=None)
@given(text=st.one_of(st.text(max_size=12), st.floats(allow_nan=True, allow_infinity=True).map(repr),
                      st.integers(-10**6, 10**6).map(str)),
       low=st.one_of(st.none(), st.floats(-1e3, 1e3)), span=st.one_of(st.none(), st.floats(0, 1e3)),
       low_open=st.booleans(), integer=st.booleans())
def test_check_number_returns_only_finite_values_in_range(text, low, span, low_open, integer):
    high = None if span is None or low is None else low + span
    try:
        value = check_number(text, low, high, low_open, integer)
    except ValueError as exc:
        assert "must be" in str(exc) and "got" in str(exc)
        return
    assert math.isfinite(value)
    assert isinstance(value, int) if integer else isinstance(value, float)
    if low is not None:
        assert value > low if low_open else value >= low
    if high is not None:
        assert value <= high


@settings(max_examples=200, deadline=None)
@given(rotor_hz=st.floats(1, 5000), strobe_hz=st.floats(1, 1000), frames=st.integers(2, 2000))
def test_strobe_coverage_refuses_exactly_the_still_and_undersampled_clips(rotor_hz, strobe_hz, frames):
    problem = strobe_coverage_problem(rotor_hz, strobe_hz, frames)
    ratio = rotor_hz / strobe_hz
    apparent = abs(ratio - round(ratio)) * strobe_hz
    if apparent < 1e-9 * strobe_hz:
        assert problem is not None and "0 Hz" in problem
    elif frames * apparent / strobe_hz >= 1.0 and apparent < 0.45 * strobe_hz:
        # a whole apparent cycle, away from half the frame rate: phases spread round the circle
        assert problem is None, problem
    if problem is not None:
        assert "--strobe-hz" in problem or "--frames" in problem


def test_a_long_simulation_announces_its_estimated_time(monkeypatch, capsys):
    import labkit.cli.simulate as simulate_cli

    monkeypatch.setattr(simulate_cli, "ESTIMATE_SAY_S", 0.0)  # every run counts as long here
    code, out, err = cli(["simulate", "conical_5_1", "--cycles", "2000"], capsys)
    assert code == 0, err
    assert "labkit simulate: 2000 cycles will take about" in err and "(a 20-cycle pilot took" in err
    code, out, err = cli(["simulate", "conical_5_1", "--cycles", "999"], capsys)
    assert code == 0 and "will take about" not in err  # short runs are not piloted


def test_a_map_point_far_too_slow_is_a_falling_floator_not_a_crash(tmp_path, capsys):
    store = tmp_path / "map.jsonl"
    code, out, err = cli(["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm",
                          "--map", "tilt_deg=5", "speed_rpm=250,25000", "--out", store], capsys)
    assert code == 0, err
    rows = {r["speed_rpm"]: r for r in map(json.loads, store.read_text().splitlines()) if "speed_rpm" in r}
    assert rows[250]["bound"] is False and rows[250]["verdict"].startswith("no bound state at 250 rpm")
    assert rows[25000]["bound"] is True
