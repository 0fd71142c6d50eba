"""``labkit report SESSION|RESULT [--out DIR]``: a self-contained report folder.

Markdown (report.md) with rig and run metadata, the data table (data.csv), fits with
uncertainties and residual plots (PNG), a model comparison, and for video results a contact
sheet of frames with the fitted pattern.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from labkit.cli.names import FIT_MODELS
from labkit.cli.output import add_json_argument, write_json
from labkit.cli.summaries import COMMAND_SUMMARIES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help=COMMAND_SUMMARIES["report"],
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", help="session directory, results JSON, CSV, or video analysis JSON")
    p.add_argument("--out", help="output folder (default: SESSION/report or RESULT-report)")
    p.add_argument("--model", choices=list(FIT_MODELS), help="fit this model only (needed for plain CSVs "
                   "whose columns do not say what they are)")
    p.add_argument("--x", help="x column for --model")
    p.add_argument("--y", help="y column for --model")
    p.add_argument("--inertia", type=float, metavar="KG_M2",
                   help="floator moment of inertia (default: from the session's rig.toml)")
    p.add_argument("--overlay", action="append", default=[], metavar="CSV",
                   help="draw curves from a CSV on the fit figures (first column x, others y, matched "
                   "by column name); repeatable")
    add_json_argument(p, "where the report and its files are")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from labkit.fit.overlay import overlays_from_csv
    from labkit.report.build import build_report

    overlays = tuple(ov for csv in args.overlay for ov in overlays_from_csv(csv))
    # a note for a person at a terminal; on a pipe or in a script stderr keeps only what went wrong
    # (a missing or bad source stays a one-line error)
    if Path(args.source).exists() and sys.stderr.isatty():
        print(f"labkit report: fitting and drawing {args.source} (a few seconds)...", file=sys.stderr,
              flush=True)
    path = build_report(args.source, args.out, model=args.model, x=args.x, y=args.y,
                        inertia=args.inertia, overlays=overlays)
    print(f"report written: {path}")
    print(f"figures and data next to it in {path.parent}")
    files = sorted(str(f) for f in path.parent.iterdir() if f.is_file())
    write_json({"report": str(path), "folder": str(path.parent), "files": files}, args.json, "report")
    return 0
