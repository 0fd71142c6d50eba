"""The robustness suite: its case specs, and a small seeded subset of easy cases rendered by the
independent renderer and analysed by labkit's public analysis, held to the issue's tolerances.

Cases the analysis on this branch does not yet pass are marked ``xfail`` with the reason (not
strict: the analysis fixes of issue 11 live on other branches; the lead re-runs this subset after
merging them, and a passing case then shows as XPASS, a hint to drop its marker)."""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import FrozenInstanceError

import pytest

from labkit.cli import main
from labkit.footage.suite import DIFFICULTIES, FAMILIES, suite_cases
from labkit.footage.suite_build import build_shot
from labkit.footage.suite_eval import evaluate_case, render_case, score_laser, score_strobe

SUBSET = {
    "circle-00-easy": None,
    "circle-09-easy": None,  # the labkit.sim cone
    "ellipse-01-easy": None,  # the labkit.sim cone on a tilted screen
    "ellipse-04-easy": None,
    "epitrochoid-2-04-easy": None,
    "epitrochoid-5-04-easy": None,
    "epitrochoid-7-00-easy": None,
    "hypotrochoid-3-04-easy": None,
    "hypotrochoid-6-04-easy": None,
    # 320x240 bodies 19-21 px from centre to corner, lens-blurred: once right but called doubtful
    # (tilt resolution), now measured by moments linear in intensity and ok
    "strobe-cylinder-12-easy": None,
    "strobe-cuboid-21-easy": None,  # a plate magnet: its long side lies across its dipole axis
}
#: small blurred bodies that were outside the tilt tolerance with the soft mask's axis (+6.7 %)
SMALL_BLURRED = ["strobe-cylinder-36-easy"]


def test_suite_has_at_least_200_cases_over_every_family_and_difficulty():
    cases = suite_cases()
    assert len(cases) >= 200
    assert len({c.name for c in cases}) == len(cases)
    assert set(Counter(c.family for c in cases)) == set(FAMILIES)
    per = Counter((c.family, c.difficulty) for c in cases)
    assert all(per[(f, d)] >= 6 for f in FAMILIES for d in DIFFICULTIES)
    loops = {(c.family, c.loops) for c in cases if c.loops}
    assert loops == {("epitrochoid", n) for n in range(2, 8)} | {("hypotrochoid", n) for n in range(3, 8)}
    laser = [c for c in cases if c.family != "strobe"]
    assert min(c.arc_cycles for c in laser) <= 0.1 and max(c.arc_cycles for c in laser) >= 3
    assert {c.size for c in cases} >= {(320, 240), (1920, 1080)}
    assert any(c.photo for c in cases) and any(not c.photo for c in laser)
    strobe = [c for c in cases if c.family == "strobe"]
    assert {c.body for c in strobe} == {"cylinder", "cuboid"}
    assert {c.rest_deg for c in strobe} >= {0.0, 90.0}
    assert {c.flashes for c in strobe} >= {0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0}
    assert {c.apparent_cpf > 0 for c in strobe} == {True, False}
    assert {c.rolling for c in strobe} == {True, False} and {c.harmonic for c in strobe} == {1, 2}


def test_cases_are_frozen_and_deterministic():
    a, b = suite_cases(limit=12), suite_cases(limit=12)
    assert a == b
    with pytest.raises(FrozenInstanceError):
        a[0].seed = 3
    assert build_shot(a[1]) == build_shot(b[1])
    assert suite_cases(only="strobe", difficulty="hard", limit=3) == [
        c for c in suite_cases() if c.family == "strobe" and c.difficulty == "hard"][:3]


def test_scoring_applies_the_tolerances():
    truth = {"pattern": {"type": "epitrochoid", "center_px": [100.0, 100.0], "semi_axes_px": [130.0, 70.0],
                         "loops": 4, "trochoid": {"a": 1 / 3, "b": 0.3}}, "camera_moves": False}
    good = {"pattern": {"type": "epitrochoid", "center_px": [100.6, 100.5], "semi_axes_px": [131.5, 70.0],
                        "loops": 4, "trochoid": {"a": 1 / 3, "b": 0.34}}}
    assert score_laser(good, truth)[0] == []
    bad = json.loads(json.dumps(good))
    bad["pattern"]["center_px"] = [101.0, 100.5]  # 1.1 px off
    bad["pattern"]["loops"] = 5
    assert score_laser(bad, truth)[0] == ["centre", "loops"]
    assert score_laser(bad, {**truth, "camera_moves": True})[0] == ["loops"]  # 1 % of 260 px = 2.6 px
    st = {"tilt_amplitude_rad": 0.08, "lateral_amplitude_px": 6.0}
    assert score_strobe({"tilt_amplitude_rad": 0.0839, "lateral_amplitude_px": 6.45}, st)[0] == []
    off = {"tilt_amplitude_rad": 0.0851, "lateral_amplitude_px": 6.6}
    assert score_strobe(off, st)[0] == ["tilt", "lateral"]


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(reason=r, strict=False)) if r else n
                                  for n, r in SUBSET.items()])
def test_easy_case_within_tolerance(name, tmp_path_factory):
    (case,) = [c for c in suite_cases(difficulty="easy") if c.name == name]
    outcome = evaluate_case(case, tmp_path_factory.getbasetemp() / "footage-suite")
    assert outcome.passed, (outcome.reported, outcome.failures, outcome.errors, outcome.message)
    if outcome.verdict is not None:  # once the analysis gives verdicts, a right easy case says ok
        assert outcome.verdict == "ok"


#: medium and hard cases whose burnt-in timestamp lies 2-3 line widths below the pattern (320x240):
#: before the stray-light grouping linked points within 1.5 line widths and kept only groups inside
#: the pattern's hull, the timestamp joined the pattern and these read as an ellipse 8 and 36 px off
#: centre and an ellipse instead of a 5-loop epitrochoid, all with verdict failed
TIMESTAMP_NEAR_PATTERN = ("circle-16-medium", "ellipse-12-hard", "epitrochoid-5-00-hard")


@pytest.mark.parametrize("name", TIMESTAMP_NEAR_PATTERN)
def test_timestamp_beside_the_pattern_is_left_out(name, tmp_path_factory):
    (case,) = [c for c in suite_cases() if c.name == name]
    outcome = evaluate_case(case, tmp_path_factory.getbasetemp() / "footage-suite")
    assert outcome.passed, (outcome.reported, outcome.failures, outcome.errors, outcome.message)
    assert outcome.verdict == "ok"


def test_a_camera_wandering_six_times_as_far_as_the_hard_preset_is_followed(tmp_path):
    """epitrochoid-4-05-hard (640x480, 0.2 of a cycle per frame) rendered again with the tripod
    wandering by 18 px instead of 3 and shaking by 1 px (as analysis/laser_wander_stress.py): the
    camera moves 28 x 33 px. Before the stray-light grouping it read as a hypotrochoid 59 px off;
    before chunks were moved by a coarse shift first (labkit.vision.laser.wander), 10 px off."""
    from dataclasses import replace

    from labkit.footage.laser_scene import laser_truth, render_laser
    from labkit.footage.mount import Mount
    from labkit.footage.output import write_footage
    from labkit.vision.laser.analyse import analyse_laser

    (case,) = [c for c in suite_cases() if c.name == "epitrochoid-4-05-hard"]
    shot = build_shot(case)
    mount = Mount(shot.mount.drift_px_s, 18.0, 1.0, case.seed, shot.mount.t_ref)
    shot = replace(shot, mount=mount)
    truth = laser_truth(shot)
    path = write_footage(tmp_path / "wander.mp4", render_laser(shot), shot.camera.fps, truth)
    result = analyse_laser(str(path))
    failures, errors = score_laser(result.to_json(), truth)
    assert failures == [], errors
    assert result.quality.verdict != "failed"


@pytest.mark.parametrize("name", SMALL_BLURRED)
def test_small_blurred_strobe_body_within_tolerance(name, tmp_path_factory):
    """Right; the verdict may still say doubtful, but only because the body is small for its tilt
    (19 px from centre to corner: a 0.1 px bias at its ends is 0.0052 rad against 0.005)."""
    (case,) = [c for c in suite_cases(difficulty="easy") if c.name == name]
    outcome = evaluate_case(case, tmp_path_factory.getbasetemp() / "footage-suite")
    assert outcome.passed, (outcome.failures, outcome.errors, outcome.message)
    assert outcome.verdict in ("ok", "doubtful")


def test_render_case_writes_footage_and_truth_once(tmp_path):
    case = suite_cases(only="circle", difficulty="easy", limit=1)[0]
    path, truth = render_case(case, tmp_path)
    assert path.exists() and path.with_name(path.stem + ".truth.json").exists()
    assert truth["case"]["name"] == case.name and truth["pattern"]["type"] == "circle"
    stamp = path.stat().st_mtime_ns
    assert render_case(case, tmp_path)[1] == truth and path.stat().st_mtime_ns == stamp  # from the cache


def test_bench_vision_suite_prints_rates_confusion_and_verdict_counts(capsys, tmp_path):
    out_json = tmp_path / "suite.json"
    rc = main(["bench", "vision", "--suite", "--only", "hypotrochoid", "--difficulty", "easy", "--limit", "1",
               "--cache", str(tmp_path / "cache"), "--json", str(out_json)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "hypotrochoid" in out and "confusion (rows: true kind" in out
    assert "outside tolerance but verdict ok:" in out and "doubtful but right:" in out
    data = json.loads(out_json.read_text())
    assert data["summary"]["cases"] == 1 and len(data["cases"]) == 1
    assert data["cases"][0]["case"]["family"] == "hypotrochoid"


def test_bench_vision_suite_rejects_an_unknown_family(capsys):
    assert main(["bench", "vision", "--suite", "--only", "spiral"]) == 2
    assert "unknown family 'spiral'" in capsys.readouterr().out


#: 320x240 hypotrochoids whose small loops (|k| b = 1.08) are filled in by a 6-8 px line: the
#: fit grew its loops into the thick tips and read the outer extent 6 % and 25 % long with verdict
#: ok; the tips-lit check and the b set where the light ends (labkit.vision.laser.loops_seen) fix both
FILLED_LOOPS = ("hypotrochoid-3-00-hard", "hypotrochoid-7-00-medium")


@pytest.mark.parametrize("name", FILLED_LOOPS)
def test_filled_in_loops_are_read_from_where_the_light_ends(name, tmp_path_factory):
    (case,) = [c for c in suite_cases() if c.name == name]
    outcome = evaluate_case(case, tmp_path_factory.getbasetemp() / "footage-suite")
    assert outcome.verdict in ("ok", "doubtful", "failed")
    assert outcome.passed or outcome.verdict != "ok", (outcome.failures, outcome.errors)  # never wrong but ok
    assert outcome.passed, (outcome.reported, outcome.failures, outcome.errors)


#: a burnt-in timestamp (1920x1080 photo) or a stray reflection (320x240 video) inside the box of
#: the pattern grown by a quarter: grouped with the pattern, it misled the fit (a 6-loop epitrochoid
#: read as a 7-loop hypotrochoid, a 3-loop one as 7 loops); the second reading sets it apart
STRAY_NEAR = ("epitrochoid-6-07-hard", "epitrochoid-3-04-hard")


@pytest.mark.parametrize("name", STRAY_NEAR)
def test_stray_light_beside_the_pattern_is_set_apart(name, tmp_path_factory):
    (case,) = [c for c in suite_cases() if c.name == name]
    outcome = evaluate_case(case, tmp_path_factory.getbasetemp() / "footage-suite")
    assert outcome.passed, (outcome.reported, outcome.failures, outcome.errors)
    assert outcome.verdict == "ok"
