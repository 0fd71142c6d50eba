"""``labkit replay SESSION``: re-run a session's protocol against its own serial cassettes.

Every port is served from ``SESSION/cassettes/ROLE.jsonl`` (strict: what the drivers send
must match the recording byte for byte), on a virtual clock, so a recorded run replays in
seconds. The results are compared with the session's ``results.json``; any difference is
printed and the exit status is 1. ``--export-csv`` instead writes ``readings/*.csv``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from labkit.cli.output import add_json_argument, announce_rerun_file, write_json
from labkit.cli.run import close_sinks
from labkit.protocols.events import FlagTally
from labkit.protocols.launch import replay_session
from labkit.session import export_csv, load_session
from labkit.stream import add_rerun_argument


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replay",
        help="re-run a session against its cassettes and check its results",
        description=__doc__.split("\n\n")[1] if __doc__ else None,
    )
    p.add_argument("session", help="session directory")
    p.add_argument("--export-csv", action="store_true", help="only export readings/*.jsonl to CSV")
    add_json_argument(p, "the comparison (identical, differences, status, results)")
    add_rerun_argument(p)
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    from labkit.stream import run_sink

    if args.export_csv:
        record = load_session(args.session)
        problems: list[str] = []
        for path in export_csv(record.path, problems):
            print(path)
        for warning in problems:
            print(f"labkit replay: warning: {warning}", file=sys.stderr)
        return 0
    flags = FlagTally()
    sinks: list = [flags]
    if args.rerun is not None:  # the same rerun sink as `labkit run`
        sinks.append(run_sink(args.rerun, None))
    try:
        result = replay_session(Path(args.session), sinks=sinks)
    finally:
        close_sinks(sinks, "replay")
    announce_rerun_file(args.rerun, "replay")
    for warning in result.warnings:
        print(f"labkit replay: warning: {warning}", file=sys.stderr)
    out = result.outcome
    write_json({"session": str(args.session), "identical": result.identical,
                "differences": result.differences, "status": out.status, "reason": out.reason,
                "warnings": result.warnings, "results": out.results}, args.json, "replay")
    if flags.counts:
        print(f"device flags: {flags.summary()}")
    if out.status != "completed" and out.error is not None and result.recorded is None:
        print(f"labkit replay: {out.status}: {out.reason}", file=sys.stderr)
        return 2
    if result.identical:
        n = len((out.results or {}).get("points", []))
        print(f"replayed {args.session}: {n} points, results identical to results.json "
              "(points exact, fits within relative 1e-6)")
        return 0
    print(f"labkit replay: results differ from {args.session}/results.json:", file=sys.stderr)
    for line in result.differences[:20]:
        print(f"  {line}", file=sys.stderr)
    if out.status != "completed":
        print(f"  the replayed run ended {out.status}: {out.reason}", file=sys.stderr)
    if load_session(args.session).meta.get("clock") == "real":
        print(
            "  (this session was recorded on a real clock: the order of commands depends on timing, "
            "so only emulator sessions on the virtual clock replay exactly)",
            file=sys.stderr,
        )
    return 1
