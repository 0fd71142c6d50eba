"""Every file a command writes is named on the terminal (issue 18, item 4)."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.cli import main


@pytest.fixture(scope="module")
def session(tmp_path_factory) -> Path:
    import labkit

    root = tmp_path_factory.mktemp("s")
    rig = Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml"
    prep = labkit.prepare_run(str(rig), "speed-sweep", ["speeds_rpm=6000:9000:n=4", "record_s=1"],
                              clock="virtual", session_root=str(root))
    return Path(labkit.execute(prep, str(root)).session)


def test_fit_names_its_plot_json_and_recording(session: Path, tmp_path: Path, capsys) -> None:
    plot, doc, rrd = tmp_path / "fit.png", tmp_path / "fit.json", tmp_path / "fit.rrd"
    assert main(["fit", str(session), "--model", "power-law", "--plot", str(plot), "--json", str(doc),
                 "--rerun", f"save:{rrd}"]) == 0
    err = capsys.readouterr().err
    for path in (plot, doc, rrd):
        assert path.is_file() and f"wrote {path}" in err, err


def test_run_names_its_recording(tmp_path: Path, capsys) -> None:
    rrd = tmp_path / "run.rrd"
    assert main(["run", "emulated-fig525", "speed-sweep", "--set", "speeds_rpm=6000", "--sessions",
                 str(tmp_path / "s"), "--no-progress", "--rerun", f"save:{rrd}"]) == 0
    assert rrd.is_file() and f"labkit run: wrote {rrd} (rerun recording" in capsys.readouterr().err


def test_synth_names_the_clip_and_its_truth(tmp_path: Path, capsys) -> None:
    clip = tmp_path / "c.mp4"
    assert main(["synth", "laser", str(clip), "--size", "96x64", "--frames", "4"]) == 0
    out = capsys.readouterr().out
    truth = tmp_path / "c.truth.json"
    assert clip.is_file() and truth.is_file()
    assert f"wrote {clip}" in out and str(truth) in out
