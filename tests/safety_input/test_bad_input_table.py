"""Issue 17, deliver 9: zero tracebacks on bad input. Each case feeds one bad input to the real
CLI (in this process, through ``labkit.cli.main``) and expects exit 2, one line on stderr that
names the file, key or device, and no traceback (an exception escaping ``main`` fails the case).

Cases are ``(name, build)`` where ``build(tmp_path, session)`` prepares the input (``session`` is
a copy of a complete emulated speed-sweep) and returns ``(argv, text the line must contain)``.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from labkit.cli import main

from .conftest import FIG525, SWEEP

JUNK = bytes(range(256)) * 4 + b"\xff\xfe\x00\x80"
DEEP = b"[" * 100_000 + b"]" * 100_000
DEEP_OBJ = b'{"a":' * 100_000 + b"1" + b"}" * 100_000


def png_header(width: int, height: int) -> bytes:
    """A PNG that declares ``width`` x ``height`` RGB pixels (an image bomb's header) with a
    tiny, truncated image stream."""
    import struct
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0" * 1000)) \
        + chunk(b"IEND", b"")


def _write(path: Path, data: bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)
    return path


def session_file_case(name: str, data: bytes, command: str, needle: str | None = None):
    """Replace ``name`` inside the session with ``data``, then run ``command`` on the session."""

    def build(tmp: Path, session: Path):
        _write(session / name, data)
        argv = {
            "resume": ["run", "--resume", session, "--dry-run"],
            "replay": ["replay", session],
            "export": ["replay", session, "--export-csv"],
            "report": ["report", session, "--out", tmp / "report"],
            "fit": ["fit", session, "--model", "power-law"],
        }[command]
        return argv, needle or name.split("/")[-1]

    return build


def file_case(filename: str, data: bytes, command: str, needle: str | None = None):
    def build(tmp: Path, session: Path):
        path = _write(tmp / filename, data)
        argv = {
            "fit": ["fit", path, "--model", "power-law"],
            "fit-folder": ["fit", path.parent, "--model", "power-law"],
            "report": ["report", path, "--out", tmp / "report"],
            "run": ["run", path, "speed-sweep", "--dry-run"],
            "predict": ["predict", path, "--speed-rpm", "12000"],
            "simulate": ["simulate", path],
            "emulate": ["emulate", path, "--seconds", "0"],
            "resume-path": ["run", "--resume", path, "--dry-run"],
            "analyse": ["analyse", "laser", path],
            "overlay": ["report", session, "--out", tmp / "report", "--overlay", path],
        }[command]
        return argv, needle or filename

    return build


def argv_case(argv: list[str], needle: str):
    def build(tmp: Path, session: Path):
        return [a.replace("{FIG525}", str(FIG525)) for a in argv], needle

    return build


CASES: dict[str, object] = {}
for fname in ("run.json", "results.json", "events.jsonl", "rig.toml"):
    for label, data in (("junk", JUNK), ("deep", DEEP)):
        for command in ("resume", "replay", "report", "fit"):
            if fname == "events.jsonl" and command in ("report", "fit"):
                continue  # report and fit read results.json, not the event log
            if fname == "rig.toml" and command in ("report", "fit"):
                continue  # the report reads the rig only for the floator's inertia (optional)
            if fname == "results.json" and command == "resume":
                continue  # resume rebuilds results from the events
            if fname == "events.jsonl":
                continue  # a damaged event line is skipped with a warning (WARN_CASES)
            CASES[f"{fname}-{label}-{command}"] = session_file_case(fname, data, command)
CASES["run.json-deep-object-resume"] = session_file_case("run.json", DEEP_OBJ, "resume")
CASES["run.json-list-resume"] = session_file_case("run.json", b"[]", "resume")
CASES["run.json-params-wrong-type"] = session_file_case(
    "run.json",
    json.dumps({"protocol": "speed-sweep", "params": {"speeds_rpm": "abc"}}).encode(),
    "resume",
    "speeds_rpm",
)
CASES["run.json-params-nan"] = session_file_case(
    "run.json", b'{"protocol": "speed-sweep", "params": {"speeds_rpm": [NaN]}}', "resume", "speeds_rpm"
)
CASES["run.json-protocol-number"] = session_file_case(
    "run.json", b'{"protocol": 5, "params": {}}', "resume", "run.json"
)
CASES["results.json-points-junk-fit"] = session_file_case(
    "results.json", b'{"points": [1, 2]}', "fit", "points[0]"
)
CASES["run.json-missing-resume"] = session_file_case("run.json.missing", b"", "resume", "run.json")
for command in ("fit", "report"):
    CASES[f"csv-junk-{command}"] = file_case("data.csv", JUNK, command)
    CASES[f"csv-nul-{command}"] = file_case("data.csv", b"speed_rpm,force_g\n1,\x002\n", command)
    CASES[f"csv-5mb-cell-{command}"] = file_case(
        "data.csv", b"speed_rpm,force_g\n1," + b"9" * 5_000_000 + b"\n", command
    )
    CASES[f"csv-5mb-quoted-{command}"] = file_case(
        "data.csv", b'speed_rpm,force_g\n1,"' + b"x" * 5_000_000 + b'"\n', command
    )
    CASES[f"json-junk-{command}"] = file_case("data.json", JUNK, command)
    CASES[f"json-deep-{command}"] = file_case("data.json", DEEP, command)
    CASES[f"json-deep-object-{command}"] = file_case("data.json", DEEP_OBJ, command)
CASES["overlay-csv-junk"] = file_case("overlay.csv", JUNK, "overlay")
CASES["overlay-csv-5mb-cell"] = file_case("overlay.csv", b"x,y\n1," + b"9" * 5_000_000 + b"\n", "overlay")
CASES["png-bomb-100000x100000"] = file_case("bomb.png", png_header(100_000, 100_000), "analyse",
                                            "the limit of 100000000")
CASES["png-bomb-12000x12000"] = file_case("bomb.png", png_header(12_000, 12_000), "analyse",
                                          "144000000 pixels, more than the limit")
CASES["png-junk"] = file_case("junk.png", JUNK, "analyse", "junk.png")
CASES["rig-junk"] = file_case("rig.toml", JUNK, "run")
CASES["rig-deep"] = file_case("rig.toml", b"a = " + b"[" * 100_000 + b"]" * 100_000, "run")
CASES["rig-big"] = file_case("rig.toml", b"# " + b"x" * 2_000_000 + b"\n", "run")
for command in ("predict", "emulate"):
    CASES[f"rig-junk-{command}"] = file_case("rig.toml", JUNK, command)
    CASES[f"rig-deep-{command}"] = file_case("rig.toml", b"a = " + b"[" * 100_000 + b"]" * 100_000, command)
    CASES[f"rig-big-{command}"] = file_case("rig.toml", b"# " + b"x" * 2_000_000 + b"\n", command)
CASES["scene-junk-simulate"] = file_case("scene.toml", JUNK, "simulate")
CASES["scene-deep-simulate"] = file_case("scene.toml", b"a = " + b"[" * 100_000 + b"]" * 100_000, "simulate")
CASES["scene-dev-zero-simulate"] = argv_case(["simulate", "/dev/zero"], "/dev/zero")
CASES["video-junk-analyse"] = file_case("clip.mp4", JUNK * 10, "analyse", "clip.mp4")
CASES["predict-dev-zero"] = argv_case(["predict", "/dev/zero", "--speed-rpm", "12000"], "/dev/zero")
CASES["emulate-dev-zero"] = argv_case(["emulate", "/dev/zero", "--seconds", "0"], "/dev/zero")
CASES["resume-a-file"] = file_case("notes.txt", b"hello", "resume-path", "notes.txt")
CASES["resume-nothing"] = argv_case(["run", "--resume", "/nonexistent/S", "--dry-run"], "/nonexistent/S")
CASES["cassette-junk-replay"] = session_file_case("cassettes/balance.jsonl", JUNK, "replay", "balance.jsonl")
CASES["cassette-deep-replay"] = session_file_case("cassettes/rotor_motor.jsonl", DEEP + b"\n", "replay",
                                                  "rotor_motor.jsonl")
CASES["fit-folder-of-junk-json"] = file_case("clips/a.json", JUNK, "fit-folder", "clips")
CASES["rig-dev-zero"] = argv_case(["run", "/dev/zero", "speed-sweep", "--dry-run"], "/dev/zero")
CASES["rig-dir"] = argv_case(["run", "/tmp", "speed-sweep", "--dry-run"], "/tmp")
CASES["set-huge-range"] = argv_case(
    ["run", "{FIG525}", "speed-sweep", "--set", "speeds_rpm=0:150000:1e-6", "--dry-run"], "speeds_rpm"
)
CASES["set-huge-list"] = argv_case(
    ["run", "{FIG525}", "speed-sweep", "--set", "speeds_rpm=" + ",".join(["6000"] * 20_000), "--dry-run"],
    "speeds_rpm",
)
CASES["set-5mb-value"] = argv_case(
    ["run", "{FIG525}", "speed-sweep", "--set", "speeds_rpm=" + "9" * 5_000_000, "--dry-run"], "speeds_rpm"
)
CASES["set-huge-repeats"] = argv_case(
    ["run", "{FIG525}", "speed-sweep", "--set", "repeats=999999999999", "--dry-run"], "repeats"
)
CASES["set-huge-int-digits"] = argv_case(
    ["run", "{FIG525}", "speed-sweep", "--set", "repeats=" + "9" * 5000, "--dry-run"], "repeats"
)
CASES["set-repeats-times-list"] = argv_case(
    [
        "run",
        "{FIG525}",
        "speed-sweep",
        "--set",
        "repeats=9000",
        "--set",
        "speeds_rpm=6000:7000:500",
        "--dry-run",
    ],
    "repeats",
)
CASES["set-tiny-step-pct"] = argv_case(
    ["run", "emulated-fig618", "spin-critical", "--set", "step_pct=1e-12", "--dry-run"], "step_pct"
)
CASES["set-nan-duration"] = argv_case(
    ["run", "{FIG525}", "speed-sweep", "--set", "record_s=nan", "--dry-run"], "record_s"
)


#: Damaged lines of an event log are skipped (docs/reference/protocols.md, Resume): exit 0, and every
#: stderr line is a warning naming ``events.jsonl:LINE``.
WARN_CASES = {
    f"events.jsonl-{label}-{command}": session_file_case("events.jsonl", data, command, "events.jsonl:")
    for label, data in (
        ("junk", JUNK + b"\n"),
        ("deep", DEEP + b"\n"),
        ("two-junk", JUNK + b"\n" + JUNK + b"\n"),
        ("long-line", b"[" + b"1," * 600_000 + b"1]\n"),
        ("not-object", b"[1, 2]\n"),
    )
    for command in ("resume", "replay")
}
WARN_CASES["readings-junk-export"] = session_file_case("readings/balance.jsonl", JUNK + b"\n", "export",
                                                       "balance.jsonl:")


@pytest.fixture(scope="module")
def complete(tmp_path_factory):
    from labkit.emulators.plant import reset_plants

    root = tmp_path_factory.mktemp("complete-table")
    reset_plants()
    assert main(["run", str(FIG525), "speed-sweep", "--sessions", str(root), *SWEEP]) == 0
    (session,) = root.iterdir()
    return session


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_input_is_one_line_naming_it(name, complete, tmp_path, capsys):
    session = tmp_path / "S"
    shutil.copytree(complete, session)
    if name == "run.json-missing-resume":
        (session / "run.json").unlink()
    argv, needle = CASES[name](tmp_path, session)
    code = main([str(a) for a in argv])  # an exception here is a traceback for a user
    out, err = capsys.readouterr()
    assert code == 2, (code, err[-500:])
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err[-2000:]
    assert len(lines[0]) < 600, lines[0][:600]
    assert needle in lines[0], (needle, lines[0])


@pytest.mark.parametrize("name", sorted(WARN_CASES))
def test_damaged_event_lines_are_warnings_naming_file_and_line(name, complete, tmp_path, capsys):
    session = tmp_path / "S"
    shutil.copytree(complete, session)
    meta = json.loads((session / "run.json").read_text())  # damaged lines come from a crash: a killed
    meta.pop("digests")                                     # run writes no digests (else: "changed")
    (session / "run.json").write_text(json.dumps(meta))
    argv, needle = WARN_CASES[name](tmp_path, session)
    target = "readings/balance.jsonl" if "readings" in name else "events.jsonl"
    good, damage = (complete / target).read_bytes(), (session / target).read_bytes()
    (session / target).write_bytes(good[: len(good) // 2].rsplit(b"\n", 1)[0] + b"\n" + damage + good[-300:])
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 0, (code, err[-500:])
    lines = err.splitlines()
    # a replay says it could not compare the run's decisions with events.jsonl's damaged lines
    unseen = [line for line in lines if "decisions were not compared" in line]
    assert len(unseen) == (1 if "replay" in name and "events" in name else 0), err[-2000:]
    assert lines and all(
        "warning" in line and needle in line and "damaged line skipped" in line
        for line in lines if line not in unseen
    ), err[-2000:]
