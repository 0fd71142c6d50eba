"""Every citation in labkit's code points to a file in this repository.

The design documents labkit was planned from live outside the repository; citing them
("PROTOCOLS 5.3", "NUMERICS.md 2.2", "ANCHORS 9.2.4", ...) leaves a reader with nothing to
open. Their relevant parts are summarised in docs/explanation/ and docs/reference/.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SOURCES = sorted([*REPO.glob("labkit/**/*.py"), *REPO.glob("labkit/data/**/*.toml")])
#: a citation of a design document outside the repository (the name ``PROTOCOLS`` alone is
#: also the protocol registry in labkit.protocols: only a section number or ``.md`` cites it)
OUTSIDE = re.compile(r"\b(ARCHITECTURE|NUMERICS|RERUN-OPENCV|ANCHORS|USER-STORIES)\b"
                     r"|\bPROTOCOLS(\.md|\s+\d)")
DOC_LINK = re.compile(r"\b(docs/[\w./-]+\.md)(#[\w-]+)?")


def _slug(heading: str) -> str:
    """A heading's anchor as GitHub makes it (lower case, punctuation dropped, spaces -> -)."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def _anchors(doc: Path) -> set[str]:
    return {_slug(line.lstrip("#")) for line in doc.read_text().splitlines() if re.match(r"#{1,6} ", line)}


def test_no_citation_of_a_document_outside_the_repository():
    found = [f"{path.relative_to(REPO)}:{n}: {line.strip()}"
             for path in SOURCES
             for n, line in enumerate(path.read_text().splitlines(), 1)
             if OUTSIDE.search(line)]
    assert found == []


def test_cited_docs_and_their_sections_exist():
    broken = []
    for path in SOURCES:
        for n, line in enumerate(path.read_text().splitlines(), 1):
            for doc, anchor in DOC_LINK.findall(line):
                target = REPO / doc
                if not target.is_file():
                    broken.append(f"{path.relative_to(REPO)}:{n}: {doc} does not exist")
                elif anchor and anchor[1:] not in _anchors(target):
                    broken.append(f"{path.relative_to(REPO)}:{n}: {doc} has no section {anchor}")
    assert broken == []


def test_the_checks_see_a_bad_citation(tmp_path):
    assert OUTSIDE.search("resync (PROTOCOLS 5.3 rule 2)") and OUTSIDE.search("NUMERICS.md T8")
    assert not OUTSIDE.search("sorted(PROTOCOLS)")
    assert _slug("`and_std` (A&D standard format)") == "and_std-ad-standard-format"
