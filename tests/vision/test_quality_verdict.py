"""The quality verdict of a laser result (labkit.vision.shared.verdict, labkit.vision.laser.checks): the
combination rule, and whole analyses of traces whose fit cannot be right, through the CLI."""

import json
import math

import cv2
import numpy as np
import pytest

from labkit.cli import main
from labkit.vision.shared.verdict import Finding, Verdict, describe, graded, in_words, rank, worst


def test_the_verdict_is_the_worst_finding_and_lists_the_reasons_of_the_others():
    found = [Finding("a", "ok"), Finding("b", "doubtful", "b is shaky"), Finding("c", "failed", "c is wrong")]
    v = Verdict.of(found).as_json()
    assert v["verdict"] == "failed"
    assert v["reasons"] == ["c is wrong", "b is shaky"]  # failed first
    assert v["checks"] == {"a": "ok", "b": "doubtful", "c": "failed"}
    alone = Verdict.of([Finding("a", "ok")]).as_json()
    assert alone == {"verdict": "ok", "reasons": [], "checks": {"a": "ok"}}
    assert worst([]) == "ok" and worst(["ok", "doubtful"]) == "doubtful"
    assert in_words(Verdict.of(found)) == "result failed: c is wrong; b is shaky"


def test_checks_made_one_by_one_give_the_same_verdict_type():
    """The strobe's way (doubt and fail as the checks run): doubts in the order found, a failure
    before every earlier reason; without named checks the JSON has no ``checks``."""
    v = Verdict()
    assert v.as_json() == {"verdict": "ok", "reasons": []}
    v.doubt("d1")
    v.fail("f1")
    v.doubt("d2")
    assert v.as_json() == {"verdict": "failed", "reasons": ["f1", "d1", "d2"]}
    v.fail("f2")
    assert v.reasons[:2] == ["f2", "f1"]
    assert describe(v) == "quality: FAILED\n  - f2\n  - f1\n  - d1\n  - d2"


def test_a_later_stage_adds_to_a_verdict_read_back_from_its_json():
    """The laser's scene and tilt-geometry checks run after the fit's verdict: a doubt keeps a
    failure, a failure reads first, and both are named among the checks."""
    first = Verdict.of([Finding("a", "ok"), Finding("b", "doubtful", "b is shaky")]).as_json()
    v = Verdict.from_json({**first, "evidence": 1.0})
    v.doubt("too far", "tilt_geometry")
    assert (v.verdict, v.reasons) == ("doubtful", ["b is shaky", "too far"])
    v.fail("not a laser", "scene")
    assert v.as_json() == {"verdict": "failed", "reasons": ["not a laser", "b is shaky", "too far"],
                           "checks": {"a": "ok", "b": "doubtful", "tilt_geometry": "doubtful",
                                      "scene": "failed"}}
    kept = Verdict.from_json({"verdict": "failed", "reasons": ["x"], "checks": {}})
    kept.doubt("y", "later")
    assert kept.verdict == "failed" and rank(kept.as_json()) == (2, 2)


def test_graded_findings_follow_their_two_limits_and_a_missing_measure_is_doubtful():
    assert graded("r", 0.4, 0.5, 2.0, "{value:.1f} widths").verdict == "ok"
    assert graded("r", 0.5, 0.5, 2.0, "{value:.1f} widths").verdict == "ok"
    d = graded("r", 1.2, 0.5, 2.0, "{value:.1f} widths")
    assert (d.verdict, d.reason) == ("doubtful", "1.2 widths")
    assert graded("r", 2.5, 0.5, 2.0, "{value:.1f} widths").verdict == "failed"
    assert graded("r", math.nan, 0.5, 2.0, "x").verdict == "doubtful"


def test_a_finding_needs_a_known_verdict_and_a_reason_unless_ok():
    with pytest.raises(ValueError, match="verdict"):
        Finding("a", "fine")
    with pytest.raises(ValueError, match="reason"):
        Finding("a", "doubtful")


def _photo(tmp_path, name, draw):
    img = np.full((720, 1280, 3), 30, np.uint8)
    draw(img)
    noise = np.random.default_rng(0).normal(0, 3, img.shape)
    path = tmp_path / name
    cv2.imwrite(str(path), np.clip(img + noise, 0, 255).astype(np.uint8))
    return path


def _analyse(capsys, path, *extra):
    out = path.with_suffix(".json")
    rc = main(["analyse", "laser", str(path), "--json", str(out), *extra])
    text = capsys.readouterr()
    assert "Traceback" not in text.out + text.err
    return rc, json.loads(out.read_text()), text


def test_a_wave_across_the_frame_fails_with_one_line_naming_the_file(tmp_path, capsys):
    """One connected stroke that no pattern of Eq. 6.38 draws: before the verdict it was printed
    as a 6-loop hypotrochoid with a 497 px semi-axis on a 1280x720 frame, exit status 0."""
    def draw(img):
        x = np.linspace(100, 1180, 400)
        y = 360 + 200 * np.sin((x - 100) / 1080 * 2 * np.pi)
        pts = np.round(np.column_stack([x, y]) * 16).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(img, [pts], False, (60, 60, 255), 5, cv2.LINE_AA, 4)

    path = _photo(tmp_path, "wave.png", draw)
    rc, r, text = _analyse(capsys, path)
    q = r["quality"]
    assert rc == 1
    assert q["verdict"] == "failed" and q["checks"]["curve covered"] == "failed"
    assert q["curve_covered"] < 1 / 3
    # stderr names the JSON written (every file written is named) and, once, the failure
    failures = [line for line in text.err.strip().splitlines() if "wrote" not in line]
    assert len(failures) == 1 and str(path) in failures[0] and "result failed" in failures[0]
    assert "quality: result failed" in text.out


def test_two_separate_lines_are_not_reported_as_an_ok_pattern(tmp_path, capsys):
    """Fitted together they made an ellipse with an 8598 px semi-axis (failed: larger than the
    frame); with the second line set apart as light away from the pattern, the result says
    that half of the light was left out."""
    def draw(img):
        cv2.line(img, (200, 200), (1000, 210), (60, 60, 255), 5, cv2.LINE_AA)
        cv2.line(img, (250, 600), (1050, 590), (60, 60, 255), 5, cv2.LINE_AA)

    rc, r, _ = _analyse(capsys, _photo(tmp_path, "lines.png", draw))
    q = r["quality"]
    assert q["verdict"] != "ok"
    assert q["checks"].get("size") == "failed" or q["light_left_out"] > 1 / 3
    assert rc == (1 if q["verdict"] == "failed" else 0)


def test_a_short_arc_of_a_huge_circle_is_not_ok(tmp_path, capsys):
    """A 20 degree arc of a 2000 px circle: any flat ellipse through it fits; most of the fitted
    curve has no light on it, and the result says so."""
    def draw(img):
        cv2.ellipse(img, (640 * 16, 2360 * 16), (2000 * 16, 2000 * 16), 0, -100, -80, (60, 60, 255), 5,
                    cv2.LINE_AA, 4)

    rc, r, text = _analyse(capsys, _photo(tmp_path, "arc.png", draw))
    q = r["quality"]
    assert q["verdict"] in ("doubtful", "failed")
    assert q["checks"]["curve covered"] != "ok"
    assert rc == (1 if q["verdict"] == "failed" else 0)
    assert f"quality: result {q['verdict']}" in text.out


def test_overlay_draws_the_fitted_curve_over_the_trace_with_the_verdict(tmp_path, capsys):
    clip = tmp_path / "ellipse.avi"
    assert main(["synth", "laser", str(clip), "--pattern", "ellipse", "--ellipticity", "0.3",
                 "--level", "easy", "--size", "320x240", "--frames", "24", "--codec", "MJPG",
                 "--seed", "4"]) == 0
    capsys.readouterr()
    png = tmp_path / "overlay.png"
    rc, r, _ = _analyse(capsys, clip, "--overlay", str(png))
    assert rc == 0 and r["quality"]["verdict"] == "ok"
    image = cv2.imread(str(png))
    assert image.shape == (240, 320, 3)
    from labkit.vision.laser.overlay import pattern_curve

    curve = pattern_curve(r["pattern"], 200)
    b, g, red = (image[np.round(curve[:, 1]).astype(int), np.round(curve[:, 0]).astype(int)].astype(int).T)
    assert np.mean((g > 150) & (g > red + 60) & (g > b + 60)) > 0.9  # the curve is drawn in green
    assert image[120:, :40].max() < 120  # away from the curve and the label: the dimmed screen


def test_overlay_to_an_unwritable_place_is_one_clear_error(tmp_path, capsys):
    clip = tmp_path / "c.avi"
    assert main(["synth", "laser", str(clip), "--pattern", "circle", "--level", "easy", "--size", "320x240",
                 "--frames", "12", "--codec", "MJPG", "--seed", "1"]) == 0
    capsys.readouterr()
    rc = main(["analyse", "laser", str(clip), "--overlay", str(tmp_path / "missing" / "o.png")])
    text = capsys.readouterr()
    assert rc == 2 and "cannot write the overlay image" in text.err and "Traceback" not in text.err


def test_rank_orders_by_verdict_then_by_how_many_checks_failed():
    one = {"verdict": "doubtful", "reasons": ["a"]}
    six = {"verdict": "doubtful", "reasons": list("abcdef")}
    assert rank({"verdict": "ok", "reasons": []}) < rank(one) < rank(six) < rank({"verdict": "failed",
                                                                                     "reasons": ["x"]})
