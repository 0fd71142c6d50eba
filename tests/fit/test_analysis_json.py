"""`labkit analyse laser|strobe --json` files as fit input: one clip, one row of cone angle
against rotor speed (Eq. 5.24); several files, folders and globs joined; bad files named."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.cli import main
from labkit.errors import DataFileError
from labkit.fit.data import analysis_kind, analysis_row, load_table, load_tables, write_table
from labkit.fit.models import cone_angle

I_KG_M2, TAU_C, TAU_S = 1e-7, 5e-3, 2e-2


def laser_doc(speed_rpm: float | None, major: float | None, minor: float | None = None,
              spin_rad_s: float | None = None, pattern: str = "ellipse") -> dict:
    """The documented layout of `labkit analyse laser --json` (docs/reference/vision-json.md), trimmed."""
    tilt = None if major is None else {"major": major, "minor": major * 0.9 if minor is None else minor}
    pat = ({"type": "none", "reason": "no light above the background noise"} if pattern == "none"
           else {"type": pattern, "center_px": [160.0, 120.0], "semi_axes_px": [50.0, 45.0]})
    return {"source": "clip.mp4", "frames": 30, "fps": 30.0, "size": [320, 240], "pattern": pat,
            "tilt_rad": tilt, "quality": {"stride": 1},
            "rotor_speed_rpm": speed_rpm, "spin_rad_s": spin_rad_s}


def strobe_doc(speed_rpm: float | None, tilt: float, spin_rad_s: float | None = None) -> dict:
    return {"source": "strobe.mp4", "frames": 48, "fps": 15.15, "apparent_hz": 0.3,
            "tilt_amplitude_rad": tilt, "lateral_amplitude_px": 14.0, "rc_offset_px": 60.0,
            "phase_source": "signal",
            "quality": {"frames_with_body": 48}, "rotor_speed_rpm": speed_rpm, "spin_rad_s": spin_rad_s}


def write(path: Path, doc) -> Path:
    path.write_text(json.dumps(doc))
    return path


def cone_folder(folder: Path, speeds_rpm=(8000, 10000, 12500, 15000, 19000), spin=None) -> list[Path]:
    """Analysis JSONs whose angles follow Eq. 5.24/5.68 exactly (spin in rad/s, or None)."""
    folder.mkdir(exist_ok=True)
    out = []
    for rpm in speeds_rpm:
        w = rpm * 2 * math.pi / 60
        phi = float(cone_angle(w, TAU_C, TAU_S, I_KG_M2, 0.0 if spin is None else spin))
        out.append(write(folder / f"c{rpm:05d}.json", laser_doc(rpm, phi, phi * 0.5, spin_rad_s=spin)))
    return out


def test_kinds_recognised_by_their_keys():
    assert analysis_kind(laser_doc(1000, 0.1)) == "laser"
    assert analysis_kind(strobe_doc(1000, 0.1)) == "strobe"
    assert analysis_kind({"protocol": "x", "points": []}) is None
    assert analysis_kind([{"tilt_rad": 1}]) is None
    from labkit.synth import laser_truth, strobe_truth
    from labkit.synth.presets import laser_preset, strobe_preset

    # the .truth.json files that `labkit synth` writes beside its clips are not analysis results
    assert analysis_kind(laser_truth(laser_preset("easy", (320, 240)))) is None
    assert analysis_kind(strobe_truth(strobe_preset("easy"))) is None


def test_laser_row_major_minor_and_spin():
    row = analysis_row(laser_doc(12000, 0.05, 0.04, spin_rad_s=12.5), "a.json")
    assert row == {"speed_rpm": 12000.0, "cone_angle_rad": 0.05, "cone_angle_minor_rad": 0.04,
                   "spin_rad_s": 12.5, "kind": "laser", "source_file": "a.json"}


def test_strobe_row():
    row = analysis_row(strobe_doc(14400, 0.21), "s.json")
    assert row == {"speed_rpm": 14400.0, "cone_angle_rad": 0.21, "kind": "strobe", "source_file": "s.json"}


@pytest.mark.parametrize("doc, message", [
    (laser_doc(None, 0.1), "a.json:rotor_speed_rpm: no rotor speed recorded (analysed without --speed-rpm); "
                           "rerun `labkit analyse laser clip.mp4 ... --speed-rpm RPM`"),
    ({k: v for k, v in laser_doc(1, 0.1).items() if k != "rotor_speed_rpm"},
     "a.json:rotor_speed_rpm: no rotor"),
    (strobe_doc(None, 0.1), "a.json:rotor_speed_rpm: no rotor speed recorded"),
    (laser_doc(9000, None),
     "a.json:tilt_rad: no tilt: analysed without --screen-distance-mm and --mm-per-px"),
    (laser_doc(9000, None, pattern="none"),
     "a.json:tilt_rad: no trace in the clip (pattern none: no light above the background noise)"),
    (laser_doc("fast", 0.1), 'a.json:rotor_speed_rpm: expected a finite number, got "fast"'),
    (laser_doc(9000, float("nan")), "a.json:tilt_rad.major: expected a finite number, got NaN"),
    (strobe_doc(9000, None), "a.json:tilt_amplitude_rad: expected a finite number, got null"),
    (laser_doc(9000, 0.1, spin_rad_s="x"), "a.json:spin_rad_s: expected a finite number"),
    (laser_doc(10 ** 400, 0.1), "a.json:rotor_speed_rpm: expected a finite number, got 1000000000"),
])
def test_unusable_clip_is_named_with_what_is_missing(tmp_path: Path, doc, message):
    path = write(tmp_path / "a.json", doc)
    with pytest.raises(DataFileError) as err:
        load_table(path)
    name, rest = message.split(":", 1)
    assert str(err.value).startswith(f"{tmp_path / name}:{rest}")


def test_one_file_is_a_one_row_table(tmp_path: Path):
    t = load_table(write(tmp_path / "a.json", laser_doc(9000, 0.08)))
    assert len(t) == 1 and t.numeric["speed_rpm"].tolist() == [9000.0]
    assert t.text["source_file"] == [str(tmp_path / "a.json")]
    assert t.meta["analysis"] == "laser" and t.meta["video"] == "clip.mp4"


def test_files_glob_and_folder_give_the_same_rows(tmp_path: Path):
    files = cone_folder(tmp_path / "clips")
    write(tmp_path / "clips" / "c08000.truth.json", {"pattern": {"type": "circle"}, "frames": 30})
    by_files = load_tables([str(p) for p in files])
    by_glob = load_tables([str(tmp_path / "clips" / "c1*.json"), str(files[0])])
    by_folder = load_tables([tmp_path / "clips"])
    assert by_files.numeric["speed_rpm"].tolist() == [8000, 10000, 12500, 15000, 19000]
    assert sorted(by_glob.numeric["speed_rpm"].tolist()) == by_files.numeric["speed_rpm"].tolist()
    np.testing.assert_array_equal(by_folder.numeric["cone_angle_rad"], by_files.numeric["cone_angle_rad"])
    assert by_folder.meta["skipped"] == ["c08000.truth.json"]
    assert by_files.text["source_file"] == [str(p) for p in files]
    assert by_files.source == f"{files[0]} ... {files[-1]} (5 files)"


def test_glob_without_match_and_folder_without_clips(tmp_path: Path):
    with pytest.raises(DataFileError, match=r"nothing\*\.json: no file matches this pattern"):
        load_tables([str(tmp_path / "nothing*.json")])
    (tmp_path / "empty").mkdir()
    write(tmp_path / "empty" / "fit.json", {"model": "cone-angle", "series": {}})
    with pytest.raises(DataFileError, match="no results.json inside .* no `labkit analyse --json` files"):
        load_tables([tmp_path / "empty"])


def test_one_bad_clip_among_many_is_named(tmp_path: Path):
    files = cone_folder(tmp_path / "clips")
    write(files[2], laser_doc(None, 0.05))
    with pytest.raises(DataFileError, match=rf"^{files[2]}:rotor_speed_rpm: no rotor speed"):
        load_tables(files)
    with pytest.raises(DataFileError, match=rf"^{files[2]}:rotor_speed_rpm"):
        load_tables([tmp_path / "clips"])


def test_spin_recorded_for_some_clips_only_is_refused(tmp_path: Path):
    files = cone_folder(tmp_path / "clips", spin=30.0)
    write(files[1], laser_doc(10000, 0.05))
    write(files[3], strobe_doc(15000, 0.02))
    with pytest.raises(DataFileError) as err:
        load_tables(files)
    text = str(err.value)
    assert text.startswith(f"{files[1]}:spin_rad_s: 3 of 5 clips record the floator spin")
    assert str(files[3]) in text and "--spin-rad-s" in text


def test_joined_with_a_csv_blanks_the_missing_columns(tmp_path: Path):
    csv = tmp_path / "hand.csv"
    csv.write_text("speed_rpm,cone_angle_rad,note\n7000,0.2,by hand\n")
    t = load_tables([csv, write(tmp_path / "a.json", strobe_doc(9000, 0.1))])
    assert t.numeric["speed_rpm"].tolist() == [7000.0, 9000.0]
    assert t.text["note"] == ["by hand", ""]
    assert t.text["source_file"] == [str(csv), str(tmp_path / "a.json")]
    assert t.text["kind"] == ["", "strobe"]


def test_written_table_reads_back(tmp_path: Path):
    files = cone_folder(tmp_path / "clips")
    t = load_tables(files)
    back = load_table(write_table(t, tmp_path / "out" / "cones.csv"))
    assert back.names == t.names
    for name, values in t.numeric.items():
        np.testing.assert_allclose(back.numeric[name], values, rtol=1e-9)
    assert back.text == t.text


@pytest.mark.parametrize("y, factor", [(None, 1.0), ("cone_angle_minor_rad", 0.5)])
def test_cli_fits_the_clips_major_or_minor(tmp_path: Path, capsys, y, factor):
    """The rows follow Eq. 5.24 with tau_C (major) and tau_C / 2 to first order (minor = phi / 2)."""
    cone_folder(tmp_path / "clips")
    args = ["fit", str(tmp_path / "clips" / "*.json"), "--model", "cone-angle", "--inertia", str(I_KG_M2),
            "--fix", f"tau_S={TAU_S}", "--json", "-"] + (["--y", y] if y else [])
    assert main(args) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["columns"]["y"] == (y or "cone_angle_rad")
    got = doc["series"]["all"]["params"]["tau_C"]["value"]
    assert got == pytest.approx(TAU_C * factor, rel=1e-6 if factor == 1.0 else 0.02)


def test_cli_uses_spin_when_every_clip_has_it(tmp_path: Path, capsys):
    """Eq. 5.68: with the spin the rows were made with, tau_C comes back exactly."""
    cone_folder(tmp_path / "clips", spin=300.0)
    assert main(["fit", str(tmp_path / "clips"), "--model", "cone-angle", "--inertia", str(I_KG_M2),
                 "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["columns"]["spin"] == "spin_rad_s"
    p = doc["series"]["all"]["params"]
    assert p["tau_C"]["value"] == pytest.approx(TAU_C, rel=1e-6)
    assert p["tau_S"]["value"] == pytest.approx(TAU_S, rel=1e-6)


def test_cli_notes_files_left_out_of_a_folder(tmp_path: Path, capsys):
    cone_folder(tmp_path / "clips")
    write(tmp_path / "clips" / "fit.json", {"model": "cone-angle"})
    table = tmp_path / "cones.csv"
    assert main(["fit", str(tmp_path / "clips"), "--model", "cone-angle", "--inertia", str(I_KG_M2),
                 "--table", str(table)]) == 0
    captured = capsys.readouterr()
    assert "left out 1 JSON file(s) that are not analysis results: fit.json" in captured.err
    assert "tau_C" in captured.out
    assert len(load_table(table)) == 5


def test_glob_leaves_out_truth_and_fit_outputs_but_lists_them(tmp_path: Path):
    """`clips/*.json` also matches `labkit synth`'s .truth.json and a fit's --json output."""
    from labkit.synth import laser_truth
    from labkit.synth.presets import laser_preset

    files = cone_folder(tmp_path / "clips")
    truth = write(tmp_path / "clips" / "c08000.truth.json", laser_truth(laser_preset("easy", (320, 240))))
    fit_out = write(tmp_path / "clips" / "fit.json", {"model": "cone-angle", "series": {}})
    t = load_tables([str(tmp_path / "clips" / "*.json")])
    assert t.text["source_file"] == [str(p) for p in files]
    assert t.meta["skipped"] == [str(truth), str(fit_out)]
    assert t.source == f"{files[0]} ... {files[-1]} (5 files)"


def test_without_analysis_json_nothing_is_left_out(tmp_path: Path):
    results = write(tmp_path / "results.json", {"points": [{"speed_rpm": 1, "force_g": 2}]})
    other = write(tmp_path / "other.json", {"model": "x"})
    with pytest.raises(DataFileError, match=rf"^{other}:points: expected a list"):
        load_tables([results, other])


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=5),
    lambda inner: (st.lists(inner, max_size=3)
                   | st.dictionaries(st.sampled_from(["major", "minor", "x"]), inner, max_size=3)),
    max_leaves=6)


@settings(max_examples=200, deadline=None)
@given(speed=json_values, tilt=json_values, spin=json_values, kind=st.sampled_from(["laser", "strobe"]))
def test_any_analysis_values_give_a_finite_row_or_a_named_error(speed, tilt, spin, kind):
    doc = laser_doc(1.0, 0.1) if kind == "laser" else strobe_doc(1.0, 0.1)
    doc.update({"rotor_speed_rpm": speed, "spin_rad_s": spin,
                ("tilt_rad" if kind == "laser" else "tilt_amplitude_rad"): tilt})
    try:
        row = analysis_row(doc, "f.json")
    except DataFileError as exc:
        assert str(exc).startswith("f.json:")
        return
    numbers = [v for k, v in row.items() if k not in ("kind", "source_file")]
    assert all(isinstance(v, float) and math.isfinite(v) for v in numbers)
    assert row["speed_rpm"] == speed and row["kind"] == kind
