"""docs/tutorials/notebook.md runs: every ```python cell, in order, in one namespace, from a folder
holding the repository's rigs/, and what each prints matches the ```text block after it
(words exactly, numbers to a relative 1e-2); the figure it writes is a PNG."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from labkit.testing.doc_pages import page_cells, run_page, same_output

REPO = Path(__file__).resolve().parents[2]
PAGE = REPO / "docs" / "tutorials" / "notebook.md"


def cells() -> list[tuple[str, str | None]]:
    """(code, expected output or None) for every python block of the page."""
    return page_cells(PAGE)



def test_the_page_walks_run_load_fit_figure() -> None:
    text = PAGE.read_text()
    for call in ("labkit.execute", "labkit.load_session", ".readings[", ".events", ".meta",
                 "labkit.fit_data", "savefig"):
        assert call in text, call
    assert len(cells()) >= 6 and all(expected is not None for _, expected in cells())
    assert not same_output("b = -1.7", "b = -1.898")


@pytest.mark.timeout(300)
def test_every_cell_runs_and_prints_what_the_page_shows(tmp_path, monkeypatch) -> None:
    os.symlink(REPO / "rigs", tmp_path / "rigs")
    monkeypatch.chdir(tmp_path)
    run_page(PAGE, "notebook_doc")
    assert (tmp_path / "force-vs-speed.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
