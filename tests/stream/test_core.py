"""--rerun specs parse to what they say; a saved .rrd reads back with what was logged."""

import argparse

import pytest
import rerun as rr

from labkit.errors import LabkitError
from labkit.stream import add_rerun_argument, open_stream, parse_rerun_spec
from labkit.stream.readback import column, entity_paths


@pytest.mark.parametrize(
    ("text", "mode", "target"),
    [
        ("spawn", "spawn", ""),
        ("connect", "connect", "rerun+http://127.0.0.1:9876/proxy"),
        ("connect:10.0.0.5:9000", "connect", "rerun+http://10.0.0.5:9000/proxy"),
        ("connect:viewer", "connect", "rerun+http://viewer:9876/proxy"),
        ("save:out/run.rrd", "save", "out/run.rrd"),
    ],
)
def test_spec_parsing(text, mode, target):
    spec = parse_rerun_spec(text)
    assert (spec.mode, spec.target) == (mode, target)


@pytest.mark.parametrize("bad", ["save", "save:", "viewer", "connect:host:port", "spawn:x"])
def test_bad_specs_say_what_is_expected(bad):
    with pytest.raises(LabkitError, match="rerun"):
        parse_rerun_spec(bad)


def test_argparse_option_rejects_bad_spec_cleanly(capsys):
    parser = argparse.ArgumentParser(prog="x")
    add_rerun_argument(parser)
    assert parser.parse_args(["--rerun", "save:a.rrd"]).rerun.target == "a.rrd"
    with pytest.raises(SystemExit):
        parser.parse_args(["--rerun", "nonsense"])
    assert "expected spawn" in capsys.readouterr().err


def test_saved_recording_reads_back(tmp_path):
    path = tmp_path / "run.rrd"
    rec = open_stream(f"save:{path}", "labkit-test")
    rec.log("/rig/speed", rr.SeriesLines(names="speed"), static=True)
    for step, value in enumerate([1.0, 2.5, 4.0]):
        rec.set_time("step", sequence=step)
        rec.log("/rig/speed", rr.Scalars(value))
    rec.disconnect()
    assert entity_paths(path) == {"/rig/speed"}
    steps, values = column(path, "/rig/speed", "Scalars:scalars", "step")
    assert steps == [0, 1, 2]
    assert [v[0] for v in values] == [1.0, 2.5, 4.0]


def test_spawn_without_display_falls_back_to_a_file(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    fallback = tmp_path / "fallback.rrd"
    rec = open_stream("spawn", "labkit-test", fallback_file=fallback)
    rec.log("/x", rr.Scalars(1.0))
    rec.disconnect()
    assert "no display" in capsys.readouterr().err
    assert fallback.exists() and entity_paths(fallback) == {"/x"}


def test_connect_with_no_viewer_saves_to_the_fallback_file(tmp_path, capsys):
    import socket

    with socket.socket() as s:   # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    fallback = tmp_path / "fallback.rrd"
    rec = open_stream(f"connect:127.0.0.1:{port}", "labkit-test", fallback_file=fallback)
    rec.log("/x", rr.Scalars(1.0))
    rec.disconnect()
    assert "no rerun viewer answers" in capsys.readouterr().err
    assert entity_paths(fallback) == {"/x"}
