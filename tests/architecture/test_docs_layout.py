"""docs/ is laid out for readers (issue 24, ADR 0029): four sections, short pages, no dead links.

* docs/ has the four sections of docs/decisions/0029-docs-for-readers.md: ``tutorials``,
  ``how-to``, ``explanation``, ``reference``; every page in them has a line in docs/README.md.
* No page under docs/ is over 600 lines.
* Every relative markdown link in docs/ and README.md points to a file that exists, and a link
  with ``#section`` to a heading of that page (anchors as GitHub makes them).

A new page at docs/ top level passes: it only has to be short and its links must resolve. It is
moved into a section (and given its line in docs/README.md) when it is merged.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SECTIONS = ("tutorials", "how-to", "explanation", "reference")
MAX_LINES = 600
#: ``[text](target)`` and ``![alt](target)``; the target ends at a space or ``)``
LINK = re.compile(r"\]\(([^)\s]+)\)")
FENCE = re.compile(r"^\s*(```|~~~)")


def _pages(root: Path) -> list[Path]:
    return sorted((root / "docs").rglob("*.md"))


def _prose_lines(page: Path) -> list[tuple[int, str]]:
    """The numbered lines of a page outside fenced code blocks (a link in code is code)."""
    lines, fenced = [], False
    for n, line in enumerate(page.read_text().splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
        elif not fenced:
            lines.append((n, line))
    return lines


def slug(heading: str) -> str:
    """A heading's anchor as GitHub makes it (lower case, punctuation dropped, spaces -> -)."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    return {slug(line.lstrip("#")) for _, line in _prose_lines(page) if re.match(r"#{1,6} ", line)}


def dead_links(root: Path) -> list[str]:
    """``page:line: target (reason)`` for every relative link that leads nowhere."""
    dead = []
    for page in [*_pages(root), root / "README.md"]:
        for n, line in _prose_lines(page):
            for target in LINK.findall(line):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                    continue  # a URL (http:, mailto:, ...) or a section of this page
                path, _, anchor = target.partition("#")
                file = (page.parent / path).resolve()
                where = f"{page.relative_to(root)}:{n}: {target}"
                if not file.exists():
                    dead.append(f"{where} (no such file)")
                elif anchor and file.suffix == ".md" and anchor not in anchors(file):
                    dead.append(f"{where} (no such section)")
    return dead


def long_pages(root: Path) -> list[str]:
    return [f"{page.relative_to(root)}: {count} lines"
            for page in _pages(root) if (count := len(page.read_text().splitlines())) > MAX_LINES]


def missing_sections(root: Path) -> list[str]:
    return [name for name in SECTIONS if not any((root / "docs" / name).glob("*.md"))]


def unindexed_pages(root: Path) -> list[str]:
    """Pages of the four sections that docs/README.md does not link to."""
    index = root / "docs" / "README.md"
    linked = {(index.parent / target.partition("#")[0]).resolve()
              for _, line in _prose_lines(index) for target in LINK.findall(line)}
    return [str(page.relative_to(root)) for name in SECTIONS
            for page in sorted((root / "docs" / name).rglob("*.md")) if page.resolve() not in linked]


def test_docs_has_the_four_sections():
    assert missing_sections(REPO) == []


def test_no_page_is_over_600_lines():
    assert long_pages(REPO) == []


def test_every_relative_link_resolves():
    assert dead_links(REPO) == []


def test_the_index_lists_every_page_of_the_sections():
    assert unindexed_pages(REPO) == []


def test_the_cli_reference_has_every_command():
    from labkit.cli import COMMANDS

    page = (REPO / "docs" / "reference" / "cli.md").read_text()
    assert [name for name in COMMANDS if f"`labkit {name}" not in page] == []


def _tree(tmp_path: Path, pages: dict[str, str]) -> Path:
    for name, text in {"README.md": "", "docs/README.md": "", **pages}.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    return tmp_path


def test_the_checks_see_a_bad_tree(tmp_path):
    root = _tree(tmp_path, {
        "docs/tutorials/a.md": "# A\n\n## First run\n\n[b](../how-to/b.md) [gone](../gone.md)\n"
                               "[bad section](b-top.md#nowhere) [good](#first-run)\n"
                               "```\n[in code](nowhere.md)\n```\n",
        "docs/tutorials/b-top.md": "# Top\n" + "x\n" * MAX_LINES,
        "docs/reference/c.md": "[a section](../tutorials/a.md#first-run) [web](https://rerun.io)\n"})
    assert missing_sections(root) == ["how-to", "explanation"]
    assert long_pages(root) == [f"docs/tutorials/b-top.md: {MAX_LINES + 1} lines"]
    assert dead_links(root) == ["docs/tutorials/a.md:5: ../how-to/b.md (no such file)",
                                "docs/tutorials/a.md:5: ../gone.md (no such file)",
                                "docs/tutorials/a.md:6: b-top.md#nowhere (no such section)"]
    assert unindexed_pages(root) == ["docs/tutorials/a.md", "docs/tutorials/b-top.md", "docs/reference/c.md"]
    (root / "docs" / "README.md").write_text("[a](tutorials/a.md) [b](tutorials/b-top.md) "
                                             "[c](reference/c.md#x)\n")
    assert unindexed_pages(root) == []


def test_slugs_are_githubs():
    assert slug("`and_std` (A&D standard format)") == "and_std-ad-standard-format"
    assert slug("Room light: the ghost of the revolution") == "room-light-the-ghost-of-the-revolution"
