"""Unusable input ends in one clear line and exit 2; a usable file without a trace gives a "none"
pattern with a reason and exit 1. Never a traceback."""

import json

import cv2
import numpy as np
import pytest

from labkit.cli import main
from labkit.synth import laser_truth, render_laser, write_clip
from labkit.synth.presets import laser_pattern, laser_preset


def run(capsys, *argv):
    rc = main(list(argv))
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, out, err


def write_frames(path, frames, fourcc="mp4v", fps=25.0):
    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, (w, h))
    assert writer.isOpened()
    for f in frames:
        assert writer.write(f) is not False
    writer.release()
    return path


def flat(level, n=12, size=(160, 120), noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(n):
        f = np.full((size[1], size[0], 3), level, np.float32)
        if noise:
            f += rng.normal(0, noise, f.shape)
            f += np.linspace(0, 30, size[0], dtype=np.float32)[None, :, None]  # a gradient, no trace
        frames.append(np.clip(f, 0, 255).astype(np.uint8))
    return frames


@pytest.mark.parametrize("kind", ["laser", "strobe"])
def test_missing_file(capsys, tmp_path, kind):
    rc, _, err = run(capsys, "analyse", kind, str(tmp_path / "nope.mp4"))
    assert rc == 2
    assert err.strip().count("\n") == 0 and "nope.mp4" in err and "no such file" in err


def test_directory_and_empty_file(capsys, tmp_path):
    rc, _, err = run(capsys, "analyse", "laser", str(tmp_path))
    assert rc == 2 and "directory" in err
    empty = tmp_path / "empty.mp4"
    empty.write_bytes(b"")
    rc, _, err = run(capsys, "analyse", "laser", str(empty))
    assert rc == 2 and "empty" in err


@pytest.mark.parametrize("name", ["junk.mp4", "junk.avi", "junk.png"])
def test_unreadable_file(capsys, tmp_path, name):
    p = tmp_path / name
    p.write_bytes(bytes(np.random.default_rng(1).integers(0, 256, 5000, dtype=np.uint8)))
    rc, _, err = run(capsys, "analyse", "laser", str(p))
    assert rc == 2 and name in err and "cannot be read" in err


def test_zero_frames(capsys, tmp_path):
    p = tmp_path / "zero.avi"
    writer = cv2.VideoWriter(str(p), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (160, 120))
    writer.release()
    rc, _, err = run(capsys, "analyse", "laser", str(p))
    assert rc == 2 and "zero.avi" in err


def test_truncated_mp4_is_unreadable(capsys, tmp_path):
    p = write_frames(tmp_path / "cut.mp4", flat(80, noise=3))
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    rc, _, err = run(capsys, "analyse", "laser", str(p))
    assert rc == 2 and "cut.mp4" in err


def test_truncated_avi_is_analysed_with_a_warning(capsys, tmp_path):
    spec = laser_preset("easy", (320, 240), seed=3)
    spec.pattern, spec.frames = laser_pattern("circle", (320, 240)), 40
    p = write_clip(tmp_path / "cut.avi", render_laser(spec), spec.fps, "MJPG", laser_truth(spec))
    p.write_bytes(p.read_bytes()[: int(p.stat().st_size * 0.6)])
    out_json = tmp_path / "cut.json"
    rc, out, _ = run(capsys, "analyse", "laser", str(p), "--json", str(out_json))
    result = json.loads(out_json.read_text())
    assert rc == 0 and result["pattern"]["type"] == "circle"
    assert result["frames"] < 40
    assert "truncated" in result["quality"]["truncated"] and "warning" in out


@pytest.mark.parametrize("kind", ["laser", "strobe"])
@pytest.mark.parametrize("level,word", [(0, "black"), (255, "white")])
def test_all_black_or_white(capsys, tmp_path, kind, level, word):
    p = write_frames(tmp_path / f"{word}.mp4", flat(level))
    rc, _, err = run(capsys, "analyse", kind, str(p))
    assert rc == 2 and word in err


def test_video_without_trace_gives_none_with_reason(capsys, tmp_path):
    p = write_frames(tmp_path / "dark-screen.mp4", flat(60, noise=4))
    out_json = tmp_path / "none.json"
    rc, _, _ = run(capsys, "analyse", "laser", str(p), "--json", str(out_json))
    result = json.loads(out_json.read_text())
    assert rc == 1
    assert result["pattern"]["type"] == "none" and result["pattern"]["reason"]
    assert result["tilt_rad"] is None


def test_strobe_without_body(capsys, tmp_path):
    p = write_frames(tmp_path / "nobody.mp4", flat(190, noise=3))
    rc, _, err = run(capsys, "analyse", "strobe", str(p))
    assert rc == 2 and "no body" in err


def test_bad_options_are_one_line_errors(capsys, tmp_path):
    p = write_frames(tmp_path / "x.mp4", flat(60, noise=4))
    rc, _, err = run(capsys, "analyse", "laser", str(p), "--roi", "5000,5000,10,10")
    assert rc == 2 and "region of interest" in err
    # --rotor-hz alone is the camera-as-strobe model (issue 11); --strobe-hz alone means nothing
    rc, _, err = run(capsys, "analyse", "strobe", str(p), "--strobe-hz", "100")
    assert rc == 2 and "--rotor-hz" in err
