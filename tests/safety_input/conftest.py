"""Shared helpers: the shipped emulated rig as text, a way to change one key, the real CLI."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.cli import main
from labkit.emulators.plant import reset_plants

REPO = Path(__file__).resolve().parents[2]
FIG525 = REPO / "rigs" / "emulated-fig525.toml"


@pytest.fixture(autouse=True)
def fresh_plants():
    reset_plants()
    yield
    reset_plants()


def rig_with(tmp_path: Path, old: str, new: str, name: str = "rig.toml") -> Path:
    """The shipped Fig. 5.25 rig with the line ``old`` replaced by ``new`` (asserted present)."""
    text = FIG525.read_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def run_cli(argv: list[str], capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line(code: int, err: str, *needles: str) -> None:
    """Exit 2, exactly one line on stderr containing every needle, and no traceback."""
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    assert err.count("\n") == 1, err
    for needle in needles:
        assert needle in err, (needle, err)


SWEEP = ["--set", "speeds_rpm=6000:12000:2000", "--set", "record_s=1.0", "--no-progress"]


@pytest.fixture(scope="module")
def complete_session(tmp_path_factory) -> Path:
    """One complete 4-step emulated speed-sweep (virtual clock, about 3 s)."""
    root = tmp_path_factory.mktemp("complete")
    reset_plants()
    assert main(["run", str(FIG525), "speed-sweep", "--sessions", str(root), *SWEEP]) == 0
    (session,) = root.iterdir()
    return session


def killed_copy(complete: Path, dest: Path, points: int = 2) -> Path:
    """A copy of ``complete`` as if killed after its ``points``-th point: events cut after that
    point, no results.json, status still running, no digests (a killed run writes none)."""
    import json
    import shutil

    session = dest / complete.name
    shutil.copytree(complete, session)
    lines = (session / "events.jsonl").read_text().splitlines(keepends=True)
    seen, cut = 0, len(lines)
    for i, line in enumerate(lines):
        if json.loads(line)["type"] == "point":
            seen += 1
            if seen == points:
                cut = i + 1
                break
    (session / "events.jsonl").write_text("".join(lines[:cut]))
    (session / "results.json").unlink()
    meta = json.loads((session / "run.json").read_text())
    meta.update(status="running", ended=None, reason=None)
    meta.pop("digests", None)
    (session / "run.json").write_text(json.dumps(meta))
    return session
