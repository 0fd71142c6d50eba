"""``labkit fit INPUT... --model NAME``: fit a session, results JSON or CSV against the PFR model.

Several inputs (files, folders, glob patterns) are joined row by row; ``labkit analyse
laser|strobe --json`` files give one row each (cone angle against rotor speed, Eq. 5.24), so
``labkit fit clips/*.json --model cone-angle --inertia I`` fits the clips of a speed series;
``--table OUT.csv`` writes the collected rows.

Prints values, standard errors, 95 % intervals and fit quality per series; ``--json OUT``
writes ``{"model", "series": {NAME: {"params": {P: {"value", "stderr", "ci95"}}, "n",
"rms_residual", "warnings"}}}``; ``--plot OUT.png`` draws data, fit and residuals.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from labkit.cli.names import FIT_MODELS, PAPER_OMEGA_C
from labkit.cli.numbers import number
from labkit.cli.output import add_json_argument, announce_rerun_file, announce_written, write_json
from labkit.cli.progress import ProgressLines
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import FitError
from labkit.stream.core import add_rerun_argument

#: resamples: percentile intervals settle to about 1 % of their width by 10 000; 100 000 is
#: several minutes of refits, 1e9 would be days
MAX_BOOTSTRAP = 100_000
BOOTSTRAP_WHY = "resamples; 10 000 give the 95 % interval to about 1 %"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fit", help=COMMAND_SUMMARIES["fit"],
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input", nargs="+",
                   help="session directory, results JSON, CSV with a header row, or `labkit analyse "
                   "--json` files (several, a folder of them or a glob pattern: one row per clip)")
    p.add_argument("--model", choices=list(FIT_MODELS),
                   help="model to fit (default: the one a session's protocol declares, e.g. "
                   "power-law for a speed sweep, spin-critical for a spin-critical series)")
    p.add_argument("--x", help="x column (default per model, see docs/reference/fitting.md)")
    p.add_argument("--y", help="y column")
    p.add_argument("--sigma", help="column of y uncertainties (default: <y>_stderr if present)")
    p.add_argument("--series", help="column that splits the data into series (default: 'series')")
    p.add_argument("--inertia", type=float, metavar="KG_M2",
                   help="floator moment of inertia for pfr-force and cone-angle "
                   "(default: a session's rig.toml [bodies.floator] inertia_radial_kg_m2)")
    p.add_argument("--omega-c", default=str(PAPER_OMEGA_C), metavar="RAD_S|fit|inf",
                   help="spin-critical: fixed omega_c (default 3000 as in Eq. 6.37), 'fit', "
                   "or 'inf' (Eq. 5.69)")
    p.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                   help="fix a parameter (SI), e.g. --fix tau_S=0 or --fix d=4; repeatable")
    p.add_argument("--bootstrap", type=number(0, MAX_BOOTSTRAP, integer=True, why=BOOTSTRAP_WHY), default=0,
                   metavar="N", help="also give bootstrap intervals (N resamples, at most "
                                     f"{MAX_BOOTSTRAP}; progress lines after 2 s)")
    p.add_argument("--seed", type=int, default=0, help="bootstrap seed")
    p.add_argument("--strict", action="store_true",
                   help="exit with status 3 when any fit has a warning (for scripts and CI)")
    add_json_argument(p, "the fit")
    p.add_argument("--plot", metavar="OUT.png", help="write data, fit and residuals as a PNG")
    p.add_argument("--table", metavar="OUT.csv",
                   help="also write the collected input rows as a CSV (e.g. speed and cone angle per clip)")
    add_rerun_argument(p)
    p.add_argument("--overlay", action="append", default=[], metavar="CSV",
                   help="draw curves from a CSV on the plot (first column x, others y, matched by "
                   "column name; e.g. a simulation at the measured speeds); repeatable")
    p.set_defaults(func=run)


def parse_omega_c(text: str) -> float | str:
    t = text.strip().lower()
    if t == "fit":
        return "fit"
    if t in ("inf", "none"):
        return math.inf
    try:
        return float(t)
    except ValueError:
        raise FitError(f"--omega-c must be a number, 'fit' or 'inf', got {text!r}") from None


def parse_fixes(items: list[str]) -> dict[str, float]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            if not sep:
                raise ValueError
            out[name.strip()] = float(value)
        except ValueError:
            raise FitError(f"--fix expects NAME=NUMBER, got {item!r}") from None
    return out


def _declared_model(inputs: list[str], table) -> str:
    """The model the input declares (a session's hints), else a clear refusal."""
    from labkit.report.build import declared_fit_model

    model = declared_fit_model(Path(inputs[0]), table) if len(inputs) == 1 else None
    if model is None or model not in FIT_MODELS:
        raise FitError(f"{' '.join(inputs)}: does not say which model fits it (no session of a known "
                       f"protocol); give --model, one of {', '.join(FIT_MODELS)}")
    print(f"labkit fit: model {model} (the one this session's protocol declares)", file=sys.stderr)
    return model


def run(args: argparse.Namespace) -> int:
    from labkit.fit.data import load_tables, write_table
    from labkit.fit.table_fit import FitOptions, fit_table
    from labkit.fit.text import format_report

    inertia = args.inertia
    if inertia is None and len(args.input) == 1 and Path(args.input[0]).is_dir():
        from labkit.report.build import floator_inertia
        inertia = floator_inertia(Path(args.input[0]))
    options = FitOptions(x=args.x, y=args.y, sigma=args.sigma, series=args.series, inertia=inertia,
                         omega_c=parse_omega_c(args.omega_c), fixed=parse_fixes(args.fix),
                         bootstrap=args.bootstrap, seed=args.seed,
                         on_progress=ProgressLines("labkit fit: bootstrap", "resamples"))
    table = load_tables(args.input)
    if args.model is None:
        args.model = _declared_model(args.input, table)
    if table.meta.get("skipped"):
        left_out = table.meta["skipped"]
        print(f"labkit fit: left out {len(left_out)} JSON file(s) that are not analysis results: "
              f"{', '.join(left_out)}", file=sys.stderr)
    if args.table:
        write_table(table, args.table)
    report = fit_table(table, args.model, options)
    print(format_report(report))
    write_json(report.to_json(), args.json, "fit")
    if args.plot:
        from labkit.fit.overlay import overlays_from_csv
        from labkit.report.figures import fit_figure
        overlays = [ov for path in args.overlay for ov in overlays_from_csv(path)]
        fit_figure(report, args.plot, overlays=overlays)
        announce_written(args.plot, "fit", "figure")
    if args.rerun is not None:
        from labkit.stream.fit_report import stream_fit_report

        stream_fit_report(args.rerun, report)
        announce_rerun_file(args.rerun, "fit")
    if args.strict and any(r.warnings for r in report.series.values()):
        print("labkit fit: warnings present (--strict)", file=sys.stderr)
        return 3
    return 0
