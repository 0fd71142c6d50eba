"""``labkit twin RIG``: the virtual twin of a rig file, measured with labkit's own instruments.

Builds the model plant from RIG's magnets and geometry (docs/explanation/twin.md), runs the Fig. 5.25 speed
sweep and the Fig. 6.18 spin-critical protocol on it through the emulated devices, renders
laser-trace and stroboscope clips of the model's floator motion (labkit.footage) and analyses
them (labkit.vision), films a cone-sweep with the emulated camera (sim://camera), fits, and
writes OUT/twin-report.md and OUT/twin-report.json: every recovered parameter beside the value
that went in, its 95 % interval and the residual. Exit status 1 when a put-in value lies
outside its interval (the rig file and the model disagree).
``--json PATH|-`` writes that JSON document to PATH too, or alone on stdout. Each part's session
can be watched in rerun afterwards: ``labkit replay SESSION --rerun save:FILE.rrd``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from labkit.cli.output import add_json_argument, write_json
from labkit.cli.summaries import COMMAND_SUMMARIES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("twin", help=COMMAND_SUMMARIES["twin"],
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("rig", help="rig file (or a bundled rig name, e.g. emulated-fig525)")
    p.add_argument("--out", type=Path, default=Path("twin"), help="report folder (default ./twin)")
    p.add_argument("--seed", type=int, default=0, help="seed of the plant's imperfections (default 0)")
    p.add_argument("--only", choices=("balance", "spin", "footage", "camera"), action="append",
                   help="run only these parts (repeatable; default: all)")
    add_json_argument(p, "the report (twin-report.json's document)")
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    from labkit.twin.report import markdown, write_report
    from labkit.twin.run import run_twin
    parts = tuple(args.only or ("balance", "spin", "footage", "camera"))
    print("labkit twin: about 14 s of CPU for the first three parts and 25 s for the camera part "
          "(docs/explanation/twin.md); a line as each starts", file=sys.stderr, flush=True)
    result = run_twin(args.rig, args.out, seed=args.seed, parts=parts,
                      say=lambda what: print(f"labkit twin: {what}", file=sys.stderr, flush=True))
    md, js = write_report(result, args.out)
    print(markdown(result), end="")
    print(f"report: {md}\n        {js}")
    write_json(json.loads(js.read_text()), args.json, "twin")
    return 0 if all(r["ok"] for r in result["rows"]) else 1
