"""docs/how-to/script-labkit.md runs: every ```python block, in order, in one namespace, from a folder
holding the repository's rigs/ and recordings/ (sessions go to a temporary folder), and what
each prints matches the ```text block after it (words exactly, numbers to a relative 1e-2)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from labkit.testing.doc_pages import page_cells, run_page, same_output

REPO = Path(__file__).resolve().parents[1]
PAGE = REPO / "docs" / "how-to" / "script-labkit.md"


def snippets() -> list[tuple[str, str | None]]:
    """(code, expected output or None) for every python block of the page."""
    return page_cells(PAGE)



def test_the_page_has_the_five_tasks():
    text = PAGE.read_text()
    for heading in ("Open a rig", "Run a protocol", "Fit", "Analyse a clip", "One device"):
        assert heading in text
    assert len(snippets()) >= 5 and all(expected is not None for _, expected in snippets())


def test_the_comparison_can_fail():
    assert same_output("b = -1.8985 (4 points)", "b = -1.898 (4 points)")
    assert not same_output("b = -1.7 (4 points)", "b = -1.898 (4 points)")
    assert not same_output("b = -1.898 (5 rows)", "b = -1.898 (4 points)")


@pytest.mark.timeout(300)
def test_every_snippet_runs_and_prints_what_the_page_shows(tmp_path, monkeypatch):
    for name in ("rigs", "recordings"):
        os.symlink(REPO / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    run_page(PAGE, "scripting_doc")
