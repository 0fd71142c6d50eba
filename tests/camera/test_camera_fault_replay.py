"""A camera that failed during a run fails again, the same way and in the same burst, when the
session is replayed (docs/reference/camera.md#frame-cassettes): the frame cassette keeps the
frames of the failed burst and a fault line, and replay raises the recorded fault where the
recorded camera raised it. Without the fault line a replay names the difference."""

from __future__ import annotations

import json
import shutil
import threading
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.devices.camera.cassette import read_cassette
from labkit.emulators import Emulation, use_emulation
from labkit.errors import CassetteError
from labkit.protocols.launch import execute, prepare_run
from labkit.protocols.replay import replay_session
from labkit.rig import bundled_rig_path

from .loopback import LoopbackMjpeg


def _rig_with_camera(tmp_path: Path, url: str) -> Path:
    text = bundled_rig_path("emulated-camera").read_text()
    start = text.index('port = "sim://camera')
    end = text.index("\n", start)
    rig = tmp_path / "rig.toml"
    rig.write_text(text[:start] + f'port = "{url}"' + text[end:])
    return rig


def _lines(session: Path) -> list[dict]:
    index = session / "cassettes" / "camera.jsonl"
    return [json.loads(line) for line in index.read_text().splitlines()[1:]]


def _without_digests(session: Path) -> None:
    # tests/session/session_edits.py's without_digests, which a test package here cannot import
    meta = json.loads((session / "run.json").read_text())
    meta.pop("digests", None)  # the edit below is the point, not the files' digests
    (session / "run.json").write_text(json.dumps(meta))


@pytest.fixture(scope="module")
def failed_virtual_session(tmp_path_factory) -> Path:
    """A virtual-clock cone sweep whose emulated camera stops after 15 frames: step 1's burst of
    10 is whole, step 2's ends after 5 frames."""
    root = tmp_path_factory.mktemp("camera-fault")
    url = ("sim://camera?seed=4&plant=model-fig525&size=160x120&fps=30&exposure_s=0.004&screen_mm=500"
           "&mm_per_px=4&stop_after=15")
    with use_emulation(Emulation("camera-fault-replay")):  # its own plant, whoever ran before
        prep = prepare_run(str(_rig_with_camera(root, url)), "cone-sweep", ["speeds_rpm=6000,9000,12000",
                           "burst_frames=10"], clock="virtual", session_root=root)
        outcome = execute(prep, session_root=root)
    assert outcome.status == "failed" and "stopped delivering frames" in (outcome.reason or "")
    session, = (p for p in root.iterdir() if p.is_dir())
    return session


def test_the_failed_burst_is_kept_with_its_fault(failed_virtual_session):
    lines = _lines(failed_virtual_session)
    assert [e["step"] for e in lines] == ["0.0"] * 10 + ["1.0"] * 5 + ["1.0"]
    fault = lines[-1]
    assert fault["fault"] == "DeviceTimeout" and fault["frames_asked"] == 10
    assert "5 of 10 frames of the burst" in fault["reason"] and fault["device"].startswith("camera camera at sim://")
    read_cassette(failed_virtual_session / "cassettes" / "camera.jsonl")  # the reader accepts it


def test_its_replay_fails_the_same_burst_the_same_way(failed_virtual_session, capsys):
    result = replay_session(failed_virtual_session)
    assert result.level == "exact" and result.identical, result.differences[:3]
    assert result.outcome.status == "failed"
    assert [d["step"] for d in result.decisions if d["decision"] == "fault"] == [1]
    assert main(["replay", str(failed_virtual_session)]) == 0
    assert "fault in step 2 as recorded" in capsys.readouterr().out


def test_without_the_fault_line_the_replay_names_the_difference(failed_virtual_session, tmp_path, capsys):
    session = tmp_path / "no-fault-line"
    shutil.copytree(failed_virtual_session, session)
    _without_digests(session)
    index = session / "cassettes" / "camera.jsonl"
    kept = [line for line in index.read_text().splitlines() if '"fault"' not in line]
    index.write_text("\n".join(kept) + "\n")
    assert main(["replay", str(session)]) == 1
    err = capsys.readouterr().err
    assert "the replay diverged" in err and "has no more frames" in err and "emulated fault" in err


@pytest.mark.parametrize("edit, problem", [
    (lambda e: {**e, "fault": "CameraOnFire"}, "fault line without a known fault"),
    (lambda e: {k: v for k, v in e.items() if k != "reason"}, "fault line without a known fault"),
    (lambda e: {**e, "t_host": "noon"}, "numeric t_host"),
])
def test_a_damaged_fault_line_is_named_by_file_and_line(failed_virtual_session, tmp_path, edit, problem):
    index = tmp_path / "camera.jsonl"
    lines = (failed_virtual_session / "cassettes" / "camera.jsonl").read_text().splitlines()
    lines[-1] = json.dumps(edit(json.loads(lines[-1])))
    index.write_text("\n".join(lines) + "\n")
    frames = (failed_virtual_session / "cassettes" / "camera.mjpeg").read_bytes()
    (tmp_path / "camera.mjpeg").write_bytes(frames)
    with pytest.raises(CassetteError) as caught:
        read_cassette(index)
    assert f"{index}:{len(lines)}" in str(caught.value) and problem in str(caught.value)


def test_a_real_camera_that_fell_silent_is_replayed_falling_silent(tmp_path, capsys, emulation):
    """Real clock, as in a lab: the camera an MJPEG stream on a loopback server that falls silent
    0.3 s into the first burst; the session's faithful replay fails that burst at its recorded
    time with the recorded fault, and reports it."""
    with LoopbackMjpeg(fps=30) as server:
        rig = _rig_with_camera(tmp_path, f"{server.url}?timeout_s=1")

        class StallWhenSettled:
            def on_event(self, event) -> None:
                kind = event.get("type") if isinstance(event, dict) else getattr(event, "type", None)
                if kind == "settled":
                    threading.Timer(0.3, server.stall.set).start()

        prep = prepare_run(str(rig), "cone-sweep", ["speeds_rpm=5000,6000"], clock="real",
                           session_root=tmp_path / "s", sinks=[StallWhenSettled()])
        outcome = execute(prep, session_root=tmp_path / "s")
    assert outcome.status == "failed" and "stopped sending frames" in (outcome.reason or "")
    session, = (tmp_path / "s").iterdir()
    assert _lines(session)[-1]["fault"] == "DeviceTimeout"
    assert main(["replay", str(session)]) == 0
    out = capsys.readouterr().out
    assert "replay level: faithful" in out and "fault in step 1 as recorded" in out
    assert "1 failed as the recorded camera failed it" in out


def test_re_analysis_and_shrink_keep_the_failed_burst(failed_virtual_session, tmp_path, capsys):
    assert main(["replay", "--analysis-only", str(failed_virtual_session)]) == 0
    assert "1 points and the fit recomputed from the recorded bytes" in capsys.readouterr().out
    shrunk = tmp_path / "shrunk"
    assert main(["shrink", "--quality", "95", str(failed_virtual_session), str(shrunk)]) == 0
    lines = _lines(shrunk)
    assert [e["step"] for e in lines] == ["0.0"] * 10 + ["1.0"] * 5 + ["1.0"] and "fault" in lines[-1]
