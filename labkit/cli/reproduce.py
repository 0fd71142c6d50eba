"""``labkit reproduce [--only PREFIX ...] [--quick] [--json OUT]``: the paper beside labkit.

Prints one line per row: id, paper value, labkit value, relative difference, agreement and
the note (known misprints and explained disagreements). ``--json`` writes the rows as a list
of ``{"id", "quantity", "paper", "labkit", "rel_diff", "ok", "note"}``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from labkit.cli.output import add_json_argument, write_json
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import LabkitError
from labkit.reproduce import SUITES, Row, run
from labkit.reproduce.paper_data import MISPRINTS


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("reproduce", help=COMMAND_SUMMARIES["reproduce"],
                            description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", action="append", metavar="PREFIX",
                        help="only rows whose id starts with PREFIX (repeatable), e.g. table5.7")
    parser.add_argument("--quick", action="store_true", help="a fast subset (seconds), as used by the tests")
    add_json_argument(parser, "the rows")
    parser.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")
    parser.set_defaults(func=main)


def _fmt(value: float | str | None) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, str):
        return value
    return f"{value:.6g}"


def format_rows(rows: list[Row]) -> str:
    """Fixed-width table of the rows (one line each)."""
    width = max([len(r.id) for r in rows] + [2])
    lines = [f"{'id':<{width}}  {'paper':>11}  {'labkit':>11}  {'rel_diff':>9}  ok  note"]
    for r in rows:
        rel = "" if r.rel_diff is None else f"{r.rel_diff:+.2e}"
        lines.append(f"{r.id:<{width}}  {_fmt(r.paper):>11}  {_fmt(r.labkit):>11}  {rel:>9}  "
                     f"{'yes' if r.ok else 'NO ':<3} {r.note}")
    return "\n".join(lines)


def _progress(start: float):
    """``labkit reproduce: [k/n] PREFIX (elapsed)`` on stderr before each suite."""
    def show(k: int, n: int, prefix: str) -> None:
        print(f"labkit reproduce: [{k}/{n}] {prefix} ({time.perf_counter() - start:.0f} s so far)",
              file=sys.stderr, flush=True)
    return show


def main(args: argparse.Namespace) -> int:
    only = args.only or []
    known = [prefix for prefix, _ in SUITES]
    for o in only:
        if not any(p.startswith(o) or o.startswith(p) for p in known):
            raise LabkitError(f"--only {o!r}: no such row prefix (known: {', '.join(known)})")
    start = time.perf_counter()
    rows = run(only, quick=args.quick, progress=None if args.no_progress else _progress(start))
    elapsed = time.perf_counter() - start
    write_json([r.as_dict() for r in rows], args.json, "reproduce")
    agree = sum(r.ok for r in rows)
    summary = f"{len(rows)} rows, {agree} agree, {len(rows) - agree} differ (see notes); {elapsed:.1f} s"
    text = "\n".join([format_rows(rows), "", summary,
                      "Known misprints in the paper (labkit uses the consistent value):"]
                     + [f"  - {m}" for m in MISPRINTS])
    try:
        print(text)
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. piped into head: not an error
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115
    return 0
