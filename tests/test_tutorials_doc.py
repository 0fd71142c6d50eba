"""The tutorials and marked how-to guides run: every ```console block of docs/tutorials/*.md and of
the docs/how-to/*.md pages that carry ``RUNS_HERE``, in order, from a folder holding the
repository's `recordings/` and `rigs/`.

A line starting ``$ labkit`` is a command (run as ``python -m labkit``; it must exit 0); the
lines after it are what it printed, each of which must be a line of its output (a tutorial may
leave lines out, never change one; words exactly, numbers to a relative 1e-2, as
``labkit.testing.doc_pages.same_output`` compares them, since fits differ in their last digits
between machines). Session folders are named by the time they were made, so
``YYYYMMDD-HHMMSS`` in a session path stands for the newest session of that protocol.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from labkit.testing.doc_pages import same_output

REPO = Path(__file__).resolve().parents[1]
#: docs/tutorials/notebook.md has its own test (tests/cli/test_notebook_doc.py): python cells, not commands
#: the mark of a how-to guide whose console blocks run here (others show long or failing runs)
RUNS_HERE = "<!-- commands run by tests/test_tutorials_doc.py -->"
TUTORIALS = sorted([*(p for p in (REPO / "docs" / "tutorials").glob("*.md") if "```console" in p.read_text()),
                    *(p for p in (REPO / "docs" / "how-to").glob("*.md") if RUNS_HERE in p.read_text())])
STAMP = re.compile(r"\d{8}-\d{6}")
SESSION = re.compile(r"sessions/\d{8}-\d{6}-([\w-]+)")


def console_blocks(text: str) -> list[list[tuple[str, list[str]]]]:
    """Each ```console block as a list of (command, expected output lines)."""
    blocks = []
    for block in re.findall(r"^```console\n(.*?)^```", text, flags=re.S | re.M):
        steps: list[tuple[str, list[str]]] = []
        for line in block.splitlines():
            if line.startswith("$ "):
                steps.append((line[2:], []))
            elif steps and line.strip():
                steps[-1][1].append(line.rstrip())
        blocks.append(steps)
    return blocks


def _newest_session(folder: Path, protocol: str) -> str:
    found = sorted((folder / "sessions").glob(f"*-{protocol}"))
    assert found, f"no session of {protocol} under {folder / 'sessions'}"
    return f"sessions/{found[-1].name}"


def _run(command: str, folder: Path) -> str:
    command = SESSION.sub(lambda m: _newest_session(folder, m.group(1)), command)
    argv = shlex.split(command)
    assert argv[0] == "labkit", f"a tutorial command that is not labkit's: {command}"
    done = subprocess.run([sys.executable, "-m", "labkit", *argv[1:]], cwd=folder, capture_output=True,
                          text=True, timeout=120)
    output = done.stdout + done.stderr
    assert done.returncode == 0, f"{command}: exit {done.returncode}\n{output}"
    return output


def missing_lines(expected: list[str], output: str) -> list[str]:
    """The expected lines that no line of ``output`` matches (session time stamps aside)."""
    actual = [STAMP.sub("STAMP", line.rstrip()) for line in output.splitlines()]
    return [line for line in expected
            if not any(same_output(got, STAMP.sub("STAMP", line)) for got in actual)]


@pytest.mark.parametrize("page", TUTORIALS, ids=[p.name for p in TUTORIALS])
def test_tutorial_commands_print_what_the_page_says(page, tmp_path):
    for name in ("recordings", "rigs"):
        (tmp_path / name).symlink_to(REPO / name)
    steps = [step for block in console_blocks(page.read_text()) for step in block]
    assert steps, f"{page.name}: a console block without a $ command"
    for command, expected in steps:
        assert missing_lines(expected, _run(command, tmp_path)) == [], command


def test_the_check_sees_a_changed_line():
    blocks = console_blocks("text\n```console\n$ labkit x\nline one\n\nline 20261127-132153\n```\n")
    assert blocks == [[("labkit x", ["line one", "line 20261127-132153"])]]
    assert missing_lines(["line one", "line 20261127-132153"], "line one  \nline 20250101-000000\n") == []
    assert missing_lines(["line one", "line two"], "line one\nline 2\n") == ["line two"]
    assert missing_lines(["b = -2.0055"], "b = -2.0061\n") == []
    assert missing_lines(["b = -2.0055"], "b = -1.9\n") == ["b = -2.0055"]
