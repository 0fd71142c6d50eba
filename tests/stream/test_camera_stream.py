"""A cone-sweep streamed to rerun (issue 25): the camera's own frames, the trace the analysis
fitted, and the live Eq. 5.24 fit drawn on the frames and against speed, recovering the model
plant's cone angles; a replay of the committed session streams the same from its cassette."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from labkit.cli import main
from labkit.devices.camera.cassette import read_cassette
from labkit.stream.readback import column, entity_paths

X = "rotor speed [RPM]"
IMAGE = "/camera/camera/image"


def _ellipse_radii(strip: list[list[float]], centre: list[float]) -> tuple[float, float]:
    """Largest and smallest distance of a drawn curve from the pattern's centre (rerun pixels)."""
    d = np.hypot(*(np.asarray(strip) - (np.asarray(centre) + 0.5)).T)
    return float(d.max()), float(d.min())


@pytest.fixture(scope="module")
def streamed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cone")
    rrd = tmp / "run.rrd"
    code = main(["run", "emulated-camera", "cone-sweep", "--sessions", str(tmp / "s"), "--no-progress",
                 "--set", "speeds_rpm=5000,6500,8000,9500", "--set", "burst_frames=12",
                 "--set", "halves=false", "--rerun", f"save:{rrd}"])
    assert code == 0
    session = next((tmp / "s").iterdir())
    return rrd, session, json.loads((session / "results.json").read_text())


def test_the_frames_are_the_cameras_own_bytes_on_the_time_timeline(streamed):
    rrd, session, results = streamed
    assert {IMAGE, f"{IMAGE}/trace", f"{IMAGE}/fit"} <= entity_paths(rrd)
    _, blobs = column(rrd, IMAGE, "EncodedImage:blob", "time")
    _, entries, data = read_cassette(session / "cassettes" / "camera.jsonl")
    stored = [data[e["offset"]:e["offset"] + e["length"]] for e in entries]
    assert len(stored) == sum(p["frames"] * (2 if p["retaken"] else 1) for p in results["points"])
    # every frame of every burst, byte for byte what the cassette holds (no re-encoding)
    assert [bytes(b[0]) for b in blobs] == stored


def test_the_live_cone_angle_fit_recovers_the_model_plant(streamed):
    rrd, _, results = streamed
    points = results["points"]
    n = len(points)
    assert n == 4 and all(p["verdict"] == "ok" for p in points)
    assert {e for e in entity_paths(rrd) if e.startswith("/eq5_24/plot/fit/")} == \
        {f"/eq5_24/plot/fit/after_{k:02d}" for k in range(3, n + 1)}
    ticks, curve = column(rrd, f"/eq5_24/plot/fit/after_{n:02d}", "Scalars:scalars", X)
    for p in points:
        y, lo, hi = curve[int(np.argmin(np.abs(np.asarray(ticks) - p["speed_rpm"])))]
        model_deg = math.degrees(p["model_cone_angle_rad"])
        assert y == pytest.approx(model_deg, rel=0.01), p   # the curve at each speed: the model's angle
        assert lo < y < hi
    # the fit's torques over I are the quick fit's (the same least squares in phi), stated tolerance
    fitted = results["fit"]["params"]
    text = _static_label(rrd, f"/eq5_24/plot/fit/after_{n:02d}")   # the legend: parameters, n
    c_live = float(text.split("tau_C/I = ")[1].split(" ")[0])
    assert c_live == pytest.approx(fitted["tau_C_over_I"]["value"], rel=1e-3)


def _static_label(rrd: Path, entity: str) -> str:
    from rerun.chunk import RrdReader

    for chunk in RrdReader(str(rrd)).stream().filter(content=entity, is_static=True):
        batch = chunk.to_record_batch()
        if "SeriesLines:names" in batch.schema.names:
            return batch.column("SeriesLines:names").to_pylist()[0][0]
    raise AssertionError(f"no legend on {entity}")


def test_every_filmed_step_shows_the_fitted_trace_and_the_live_fits_trace(streamed):
    rrd, _, results = streamed
    points = results["points"]
    ticks, traces = column(rrd, f"{IMAGE}/trace", "LineStrips2D:strips", X)
    fit_ticks, fits = column(rrd, f"{IMAGE}/fit", "LineStrips2D:strips", X)
    _, labels = column(rrd, f"{IMAGE}/fit/label", "Points2D:labels", X)
    targets = [round(p["target_rpm"]) for p in points]
    assert sorted(set(ticks)) == targets and sorted(set(fit_ticks)) == targets
    # the newest fit is logged last at every step's tick: the one the viewer shows there
    last = {t: (strip, label) for t, strip, label in zip(fit_ticks, fits, labels, strict=True)}
    trace_at = dict(zip(ticks, traces, strict=True))
    for p in points:
        strip, label = last[round(p["target_rpm"])]
        assert label[0].startswith(f"live fit after {len(points)} points: cone angle [deg] = ")
        y_fit = float(label[0].rsplit("= ", 1)[1])
        assert y_fit == pytest.approx(math.degrees(p["model_cone_angle_rad"]), rel=0.01)
        # the fit agrees with the measured angle within 0.5 %: the two drawn traces within ~1 %
        centre = _centre(trace_at[round(p["target_rpm"])][0])
        big_fit, small_fit = _ellipse_radii(strip[0], centre)
        big, small = _ellipse_radii(trace_at[round(p["target_rpm"])][0], centre)
        assert big_fit == pytest.approx(big, rel=0.02) and small_fit == pytest.approx(small, rel=0.02)


def _centre(strip: list[list[float]]) -> list[float]:
    return list(np.mean(np.asarray(strip), axis=0) - 0.5)


def test_the_fit_on_the_frames_grows_point_by_point_on_the_time_timeline(streamed):
    rrd, _, results = streamed
    _, labels = column(rrd, f"{IMAGE}/fit/label", "Points2D:labels", "time")
    grown = [int(lab[0].split("after ")[1].split(" ")[0]) for lab in labels]
    assert grown == list(range(3, len(results["points"]) + 1))


def test_a_replay_of_the_committed_session_streams_its_frames_from_the_cassette(tmp_path, capsys):
    session = Path("recordings/sessions/cone-sweep-clean")
    rrd = tmp_path / "replay.rrd"
    assert main(["replay", str(session), "--rerun", f"save:{rrd}"]) == 0, capsys.readouterr().err
    _, blobs = column(rrd, IMAGE, "EncodedImage:blob", "time")
    _, entries, data = read_cassette(session / "cassettes" / "camera.jsonl")
    assert [bytes(b[0]) for b in blobs] == [data[e["offset"]:e["offset"] + e["length"]] for e in entries]
    points = json.loads((session / "results.json").read_text())["points"]
    assert f"/eq5_24/plot/fit/after_{len(points):02d}" in entity_paths(rrd)
