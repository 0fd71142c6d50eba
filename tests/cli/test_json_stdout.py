"""``--json -`` prints exactly one JSON document on stdout and writes no file named ``-``
(issue 18, one command grammar), for every command that produces a result."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

WORKTREE = Path(__file__).resolve().parents[2]


def labkit(args: list[str], cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(WORKTREE))
    return subprocess.run([sys.executable, "-m", "labkit", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> Path:
    """A 5-step emulated speed sweep (sessions/ONE) and a small synthetic laser clip."""
    root = tmp_path_factory.mktemp("made")
    done = labkit(["run", "emulated-fig525", "speed-sweep", "--set", "speeds_rpm=6000:10000:1000",
                   "--sessions", "sessions", "--no-progress"], root)
    assert done.returncode == 0, done.stderr
    clip = labkit(["synth", "laser", "clip.mp4", "--size", "160x120", "--frames", "20"], root)
    assert clip.returncode == 0, clip.stderr
    return root


def session_of(root: Path) -> str:
    (one,) = (root / "sessions").iterdir()
    return str(one)


COMMANDS = {
    "run": lambda r: ["run", "emulated-fig525", "speed-sweep", "--set", "speeds_rpm=6000:8000:1000",
                      "--sessions", str(r / "more")],
    "replay": lambda r: ["replay", session_of(r)],
    "fit": lambda r: ["fit", session_of(r), "--model", "power-law"],
    "analyse laser": lambda r: ["analyse", "laser", str(r / "clip.mp4")],
    "predict": lambda r: ["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm",
                          "--speed-rpm", "25000", "--no-verify", "--no-limits"],
    "simulate": lambda r: ["simulate", "fig5_7", "--cycles", "20"],
    "reproduce --quick": lambda r: ["reproduce", "--quick", "--only", "table5.4"],  # one suite: the
    # JSON form is what is tested here; tests/test_reproduce.py checks the rows
    "synth": lambda r: ["synth", "laser", str(r / "other.mp4"), "--size", "160x120", "--frames", "10"],
    "report": lambda r: ["report", session_of(r), "--out", str(r / "report")],
}
#: what each document must hold (a key of the top-level object, or a list for reproduce)
EXPECTED_KEY = {"run": "status", "replay": "identical", "fit": "model", "analyse laser": "pattern",
                "predict": None, "simulate": None, "reproduce --quick": None, "synth": "video",
                "report": "report"}


@pytest.mark.timeout(900)
@pytest.mark.parametrize("name", list(COMMANDS))
def test_json_dash_is_one_document_on_stdout(name: str, made: Path, tmp_path: Path) -> None:
    done = labkit([*COMMANDS[name](made), "--json", "-"], tmp_path)
    assert done.returncode in (0, 1), done.stderr
    doc = json.loads(done.stdout)  # exactly one document: anything else on stdout fails here
    assert doc, f"{name}: empty JSON document"
    key = EXPECTED_KEY[name]
    if name == "reproduce --quick":
        assert isinstance(doc, list) and {"id", "paper", "labkit"} <= set(doc[0])
        assert "labkit reproduce: [1/" in done.stderr  # progress, on stderr
    elif key is not None:
        assert key in doc, f"{name}: {sorted(doc)}"
    assert not (tmp_path / "-").exists()
    assert not (made / "-").exists()


def test_a_dry_run_gives_its_plan_as_json(tmp_path: Path) -> None:
    done = labkit(["run", "emulated-fig525", "speed-sweep", "--set", "speeds_rpm=6000:8000:n=3", "--dry-run",
                   "--json", "-"], tmp_path)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["status"] == "dry-run" and doc["n_steps"] == 3
    assert doc["params"]["speeds_rpm"] == [6000.0, 7000.0, 8000.0]
    assert "3 steps" in done.stderr  # the human plan, moved to stderr


def test_json_path_is_named_on_stderr(made: Path, tmp_path: Path) -> None:
    out = tmp_path / "fit.json"
    done = labkit(["fit", session_of(made), "--model", "power-law", "--json", str(out)], tmp_path)
    assert done.returncode == 0, done.stderr
    assert json.loads(out.read_text())["model"] == "power-law"
    assert f"wrote {out}" in done.stderr
    assert "power-law" in done.stdout  # the human report stays on stdout when --json is a file
