"""A stroboscope clip given to `labkit analyse laser` exits 1 saying it looks like a strobe clip
(issue 27: it gave a pattern, verdict doubtful, exit 0): a dark body on a lit background (the
shipped clip) and a lit body on a dark one (`synth strobe --level hard`)."""

from __future__ import annotations

from pathlib import Path

from labkit.cli import main

VIDEOS = Path(__file__).resolve().parents[2] / "recordings" / "videos"


def test_the_shipped_strobe_clip_is_refused_as_a_laser_trace(capsys):
    assert main(["analyse", "laser", str(VIDEOS / "strobe-medium.mp4")]) == 1
    err = capsys.readouterr().err
    assert "result failed: this looks like a stroboscope clip, not a laser trace: 100 % of the frame is lit" \
        in err, err
    assert "analyse it with labkit analyse strobe" in err


def test_a_lit_body_on_a_dark_background_is_refused_too(tmp_path, capsys):
    clip = tmp_path / "dark.mp4"
    assert main(["synth", "strobe", str(clip), "--level", "hard"]) == 0
    capsys.readouterr()
    assert main(["analyse", "laser", str(clip)]) == 1
    err = capsys.readouterr().err
    assert "this looks like a stroboscope clip, not a laser trace: the light is a filled shape" in err, err


def test_laser_clips_pass_the_scene_check(capsys):
    for name in ("laser-ellipse-medium.mp4", "laser-epitrochoid4-hard.mp4", "laser-hypotrochoid3-photo.jpg"):
        assert main(["analyse", "laser", str(VIDEOS / name)]) == 0, capsys.readouterr().err
        assert "stroboscope" not in capsys.readouterr().err
