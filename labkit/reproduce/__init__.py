"""The paper-reproduction suite behind ``labkit reproduce``.

Each suite module exposes ``rows(quick: bool) -> list[Row]``; :func:`run` collects them in
order, filtered by id prefix. Rows compare a number printed in the paper with labkit's
value (closed forms of :mod:`labkit.model` or converged DOP853 integrations).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass

SUITES = [
    ("table5.4", "labkit.reproduce.planar_rows"),
    ("table5.7", "labkit.reproduce.planar_rows"),
    ("eq5.92", "labkit.reproduce.planar_rows"),
    ("eq5.485", "labkit.reproduce.one_dof_rows"),
    ("table5.5", "labkit.reproduce.pfr_rows"),
    ("table5.3", "labkit.reproduce.cone_rows"),
    ("fig5.6", "labkit.reproduce.tilted_rows"),
    ("eq5.85", "labkit.reproduce.force_law_rows"),
    ("table5.6", "labkit.reproduce.force_law_rows"),
    ("eq6.13", "labkit.reproduce.force_law_rows"),
    ("eq6.22", "labkit.reproduce.mbs_rows"),
    ("fig6.18", "labkit.reproduce.mbs_rows"),
    ("fig6.18", "labkit.reproduce.measured_rows"),
    ("fig5.25", "labkit.reproduce.measured_rows"),
    ("fig5.26", "labkit.reproduce.measured_rows"),
    ("twin", "labkit.reproduce.twin_rows"),
]


@dataclass
class Row:
    """One comparison: ``paper`` and ``labkit`` are numbers or verdict strings."""

    id: str
    quantity: str
    paper: float | str | None
    labkit: float | str | None
    rel_diff: float | None
    ok: bool
    note: str = ""

    def as_dict(self) -> dict:
        """JSON-ready: non-finite numbers become None (JSON has no NaN)."""
        out = asdict(self)
        for key in ("paper", "labkit", "rel_diff"):
            if isinstance(out[key], float) and not math.isfinite(out[key]):
                out[key] = None
        return out


def compare(row_id: str, quantity: str, paper: float | None, labkit: float, rel_tol: float,
            note: str = "", abs_tol: float = 0.0) -> Row:
    """Numeric row: ok when |labkit - paper| <= max(rel_tol |paper|, abs_tol)."""
    if paper is None or labkit is None or not math.isfinite(labkit):
        return Row(row_id, quantity, paper, labkit, None, paper is None and labkit is not None, note)
    diff = labkit - paper
    rel = diff / abs(paper) if paper != 0 else math.inf if diff else 0.0
    ok = abs(diff) <= max(rel_tol * abs(paper), abs_tol)
    return Row(row_id, quantity, paper, float(labkit), float(rel), bool(ok), note)


def verdict(row_id: str, quantity: str, paper: str, labkit: str, note: str = "") -> Row:
    """Categorical row (e.g. ``stable`` / ``unstable``)."""
    return Row(row_id, quantity, paper, labkit, None, paper == labkit, note)


def _wanted(prefix: str, only: Iterable[str] | None) -> bool:
    if not only:
        return True
    return any(prefix.startswith(o) or o.startswith(prefix) for o in only)


def run(only: Iterable[str] | None = None, quick: bool = False,
        progress: Callable[[int, int, str], None] | None = None) -> list[Row]:
    """Run the suites whose prefix matches ``only`` (any of the id prefixes; all if empty);
    ``progress(k, n, prefix)`` is called before suite k of n starts."""
    only = list(only or [])
    done: set[str] = set()
    rows: list[Row] = []
    wanted = [(p, m) for p, m in dict.fromkeys(SUITES) if _wanted(p, only)]
    for k, (prefix, module_name) in enumerate(wanted, 1):
        if (prefix, module_name) in done:
            continue
        if progress is not None:
            progress(k, len(wanted), prefix)
        module = importlib.import_module(module_name)
        for row in module.rows(quick=quick, prefix=prefix):
            if not only or any(row.id.startswith(o) for o in only):
                rows.append(row)
        done.add((prefix, module_name))
    return rows
