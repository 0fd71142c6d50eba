"""The one place a run's hints are found: its start document's, or, for sessions recorded
before the start document carried them (ADR 0021), the table below keyed by protocol name,
then by the columns of a table with no protocol (a CSV or results.json with speed and force).

The report (:mod:`labkit.report.build`) calls :func:`hints_for` and never looks at a
protocol's name itself. The rerun sink needs no table: it sees only start documents of runs
(``labkit run``, ``labkit replay``, which re-runs the protocol), and the runner writes every
protocol's hints into them.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from labkit.hints import Hints
from labkit.protocols.paper_figures import EQ_5_24, FIG_5_25, FIG_6_18

#: protocol name -> the hints its sessions had before they were written into the start document
#: (cone-sweep: the fixture recordings/sessions/cone-sweep-clean was recorded before the merge)
LEGACY_HINTS: dict[str, Hints] = {"speed-sweep": FIG_5_25, "spin-critical": FIG_6_18, "cone-sweep": EQ_5_24}


def hints_for(protocol: str | None, declared: dict[str, Any] | None = None,
              columns: Iterable[str] = ()) -> Hints | None:
    """The start document's ``declared`` hints; else the legacy hints of ``protocol``; else
    those whose x and y are both among ``columns``; else None (no figure, no fit)."""
    if declared:
        return Hints.from_json(declared)
    if protocol in LEGACY_HINTS:
        return LEGACY_HINTS[str(protocol)]
    present = set(columns)
    for hints in LEGACY_HINTS.values():
        if {hints.x, hints.y} <= present:
            return hints
    return None
