"""Bad input to `labkit run` ends with one clear line and exit 2, before any motor turns."""

import os
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.emulators.plant import shared_plant

REPO = Path(__file__).resolve().parents[2]
FIG525 = str(REPO / "rigs" / "emulated-fig525.toml")


def run_cli(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("argv, expected", [
    (["run", FIG525, "spin-critical"], "needs a tachometer device called 'floator_tach'"),
    (["run", FIG525, "speed-sweep", "--set", "speeds_rpm=20000:26000:2000"],
     "above the rig's limit of 24000 RPM"),
    (["run", FIG525, "sweep-faster"],
     "unknown protocol 'sweep-faster'; known: cone-sweep, speed-sweep, spin-critical, strobe-sweep"),
    (["run", "no-such-rig.toml", "speed-sweep"], "no-such-rig.toml:(file): no such rig file"),
])
def test_bad_input_is_one_line_and_exit_2_before_motion(argv, expected, capsys, tmp_path):
    code, out, err = run_cli([*argv, "--sessions", str(tmp_path), "--no-progress"], capsys)
    assert code == 2
    assert err.count("\n") == 1 and expected in err, err
    assert err.startswith("labkit run: ")
    assert not list(tmp_path.iterdir())                    # no session was started
    assert shared_plant("model-fig525").motor("rotor").duty_changes == []


def test_unwritable_session_directory(capsys, tmp_path):
    blocker = tmp_path / "file-not-dir"
    blocker.write_text("")
    argv = ["run", FIG525, "speed-sweep", "--sessions", str(blocker / "s"), "--no-progress"]
    code, out, err = run_cli(argv, capsys)
    assert code == 2 and err.count("\n") == 1
    assert "session directory is not writable" in err
    assert shared_plant("model-fig525").motor("rotor").duty_changes == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write anywhere")
def test_read_only_session_directory(capsys, tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o500)
    code, out, err = run_cli(["run", FIG525, "speed-sweep", "--sessions", str(ro), "--no-progress"], capsys)
    assert code == 2 and "not writable" in err


def test_dry_run_prints_the_plan_and_moves_nothing(capsys, tmp_path):
    code, out, err = run_cli(["run", FIG525, "speed-sweep", "--dry-run", "--set", "speeds_rpm=6000,9000",
                              "--sessions", str(tmp_path)], capsys)
    assert code == 0
    assert "2 steps" in out and "up 9000 RPM" in out
    assert not list(tmp_path.iterdir())
    assert shared_plant("model-fig525").motor("rotor").duty_changes == []


def test_resuming_a_finished_session_is_refused(capsys, tmp_path):
    done = REPO / "recordings" / "sessions" / "speed-sweep-clean"
    argv = ["run", "--resume", str(done), "--sessions", str(tmp_path), "--no-progress"]
    code, out, err = run_cli(argv, capsys)
    assert code == 2 and "all 4 steps are already done" in err
    assert not list(tmp_path.iterdir())


def test_bundled_rig_by_name_after_a_plain_install(capsys):
    code, out, err = run_cli(["run", "emulated-fig618", "spin-critical", "--dry-run"], capsys)
    assert code == 0 and "spin-critical on emulated-fig618" in out
