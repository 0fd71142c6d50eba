"""labkit analyse --rerun save:FILE logs the frames and the fitted pattern where the analysis found it."""

import json

import numpy as np

from labkit.cli import main
from labkit.stream.readback import column, entity_paths
from labkit.stream.vision import pattern_curve


def test_laser_analysis_streams_frames_and_fitted_ellipse(tmp_path, capsys):
    clip = tmp_path / "ellipse.avi"
    assert main(["synth", "laser", str(clip), "--pattern", "ellipse", "--ellipticity", "0.3",
                 "--level", "easy", "--size", "320x240", "--frames", "24", "--codec", "MJPG",
                 "--seed", "4"]) == 0
    rrd, out = tmp_path / "laser.rrd", tmp_path / "laser.json"
    assert main(["analyse", "laser", str(clip), "--json", str(out), "--rerun", f"save:{rrd}"]) == 0
    result = json.loads(out.read_text())
    assert {"/video/frame", "/video/frame/fit", "/video/frame/center", "/video/pattern",
            "/video/trace", "/video/trace/fit"} <= entity_paths(rrd)
    frames, _ = column(rrd, "/video/frame", "EncodedImage:blob", "frame")
    assert len(frames) == result["quality"]["frames_analysed"]

    # the logged curve is the reported ellipse: its extent matches the semi-axes
    curve = pattern_curve(result["pattern"])
    centred = curve - np.asarray(result["pattern"]["center_px"])
    radii = np.linalg.norm(centred, axis=1)
    major, minor = result["pattern"]["semi_axes_px"]
    assert abs(radii.max() - major) < 0.01 * major and abs(radii.min() - minor) < 0.01 * major


def test_strobe_analysis_streams_frames_and_the_point_pattern(tmp_path, capsys):
    clip = tmp_path / "strobe.avi"
    assert main(["synth", "strobe", str(clip), "--level", "easy", "--frames", "40", "--codec", "MJPG",
                 "--rotor-hz", "240", "--strobe-hz", "239.5", "--seed", "2"]) == 0
    rrd, out = tmp_path / "strobe.rrd", tmp_path / "strobe.json"
    main(["analyse", "strobe", str(clip), "--rotor-hz", "240", "--strobe-hz", "239.5",
          "--json", str(out), "--rerun", f"save:{rrd}"])
    result = json.loads(out.read_text())
    entities = entity_paths(rrd)
    assert {"/video/frame", "/video/pattern"} <= entities
    frames, _ = column(rrd, "/video/frame", "EncodedImage:blob", "frame")
    assert len(frames) == result["frames"]
    assert ("/video/frame/fit" in entities) == (result["point_pattern"]["type"] != "none")
