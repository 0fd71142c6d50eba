"""``labkit sweep table5.3 | fig5.12``: stability maps of the conical motion (paper Sec. 5.1.3, 5.1.6).

``--rows`` runs the 36 rows of Table 5.3 and compares each verdict with the paper's; otherwise
every body/drive configuration of Table 5.3 is run over ``--ratios START:STOP:n=COUNT`` of
``tau_S / tau_C`` and printed as a map (``S`` stable, ``u`` unstable) next to Eq. 5.46's
minimum ratio. Points run in chunks with the batch kernel, in this process (default), a local
process pool (``--workers``) or on a Dask cluster (``--scheduler tcp://host:8786``); with
``--out results.jsonl`` every finished chunk is saved at once and a rerun resumes from it.

``fig5.12`` maps the spinning body of Fig. 5.12 over the spin parameter ``--k`` and the ratio.
Grids that start with a minus sign are given with ``=``: ``--k=-1.5:0.25:15``.
"""

from __future__ import annotations

import argparse
import math
import sys

from labkit.cli.confirm import CONFIRM_SWEEP_POINTS, add_yes_argument, confirm_size
from labkit.cli.parsers import command_parser
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.numerics.checks import NumericsError

DEFAULT_RATIOS = "0:0.6:n=13"
FIG_5_12_RATIOS = "-4:5:n=19"
FIG_5_12_KS = "-1.5:0.25:n=15"


def register(sub: argparse._SubParsersAction) -> None:
    p = command_parser(sub, "sweep", COMMAND_SUMMARIES["sweep"], __doc__)
    p.add_argument("problem", choices=["table5.3", "fig5.12"], help="what to sweep")
    p.add_argument("--rows", action="store_true", help="the 36 rows of Table 5.3 instead of a map")
    p.add_argument(
        "--ratios",
        help=f"tau_S/tau_C grid START:STOP:n=COUNT (table5.3: {DEFAULT_RATIOS}; fig5.12: {FIG_5_12_RATIOS})",
    )
    p.add_argument(
        "--k",
        default=FIG_5_12_KS,
        help=f"fig5.12: spin parameter grid START:STOP:n=COUNT, written --k={FIG_5_12_KS} (the default)",
    )
    p.add_argument(
        "--bias", type=float, default=0.5, help="initial kick on the y angular velocity, rad/s (map)"
    )
    p.add_argument("--cycles", type=int, default=100, help="drive periods per point (default 100)")
    p.add_argument("--steps", type=int, default=64, help="steps per drive period (default 64)")
    p.add_argument("--out", metavar="RESULTS.jsonl", help="partial results on disk (resumable)")
    p.add_argument("--chunk", type=int, default=None,
                   help="points per task (default: about 4 tasks per worker slot, at least 4 points)")
    p.add_argument("--workers", type=int, default=1, help="local worker processes (default 1: in process)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://10.0.0.5:8786")
    p.add_argument("--timeout", type=float, default=10.0, help="seconds to wait for the scheduler")
    p.add_argument("--json", metavar="PATH|-", help="write all results as JSON ('-': alone on stdout)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_yes_argument(p, f"the sweep has more than {CONFIRM_SWEEP_POINTS} points")
    p.set_defaults(func=run)


def parse_ratios(text: str, option: str = "--ratios") -> list[float]:
    """``START:STOP:n=COUNT`` (inclusive, evenly spaced), ``START:STOP:step=S`` or a comma list
    (:mod:`labkit.ranges`; the old ``START:STOP:COUNT`` is refused with the new spelling)."""
    from labkit.ranges import RangeError, parse_range

    try:
        return parse_range(text, bare="error", limit=100_000)
    except RangeError as exc:
        raise NumericsError(f"{option} {exc} (e.g. 0:0.6:n=13 or a comma list)") from None


def run(args: argparse.Namespace) -> int:
    from labkit.model.stability import min_static_ratio
    from labkit.numerics import stability_map
    from labkit.numerics.checks import check_steps
    from labkit.numerics.sweep import MIN_CHUNK, run_sweep

    if args.cycles <= 0:
        raise NumericsError(f"--cycles {args.cycles}: must be positive")
    check_steps(args.steps, 1.0, 1.0, 4)
    stability_map.check_chunk(max(1, args.chunk or MIN_CHUNK), args.cycles)
    if args.problem == "fig5.12":
        points = stability_map.fig5_12_points(
            parse_ratios(args.k, "--k"), parse_ratios(args.ratios or FIG_5_12_RATIOS), bias_y=args.bias
        )
    elif args.rows:
        points = stability_map.table5_3_rows()
    else:
        points = stability_map.map_points(parse_ratios(args.ratios or DEFAULT_RATIOS), bias_y=args.bias)
    confirm_size(len(points), CONFIRM_SWEEP_POINTS, "sweep points", yes=args.yes, command="sweep")
    for p in points:  # the horizon is part of a point's identity in the store
        p["cycles"], p["steps_per_period"] = args.cycles, args.steps
    try:
        res = run_sweep(
            points,
            stability_map.Evaluator(args.cycles, args.steps),
            store=args.out,
            chunk=args.chunk,
            max_chunk=stability_map.max_chunk(args.cycles),
            workers=args.workers,
            scheduler=args.scheduler,
            timeout_s=args.timeout,
            progress=not args.no_progress,
            description=f"{args.problem} {len(points)} points",
        )
    except KeyboardInterrupt:
        if args.out:
            saved = f"finished chunks are saved in {args.out}; run the same command to resume"
        else:
            saved = "nothing was saved: give --out RESULTS.jsonl to make a sweep resumable"
        print(f"labkit sweep: interrupted; {saved}", file=sys.stderr)
        return 130
    print(
        f"{len(res.results)} points: {res.computed} computed now, {res.reused} reused from "
        f"{args.out or 'nothing'}; {args.cycles} cycles at {args.steps} steps per period each"
    )
    if args.problem == "fig5.12":
        print_fig5_12(res.results)
    elif args.rows:
        agree = 0
        print(f"{'row':>3} {'tau_S/tau_C':>11} {'labkit':>8} {'paper':>8} {'max dev rad':>11}")
        for r in res.results:
            agree += r["verdict"] == r["paper"]
            mark = "" if r["verdict"] == r["paper"] else "  <- differs"
            print(
                f"{r['row']:>3} {r['ratio']:>11.3f} {r['verdict']:>8} {r['paper']:>8} "
                f"{r['max_deviation_rad']:>11.3g}{mark}"
            )
        print(f"{agree}/{len(res.results)} verdicts agree with Table 5.3")
    else:
        ratios = sorted({r["ratio"] for r in res.results})
        print(
            "configuration (I_A, I_R kg m^2, omega rad/s, tau_C N m)    map over tau_S/tau_C "
            f"{ratios[0]:g}..{ratios[-1]:g}   first stable ratio   Eq. 5.46 min ratio"
        )
        configs = {}
        for r in res.results:
            configs.setdefault((r["i_a"], r["i_r"], r["omega"], r["tau_c"]), {})[r["ratio"]] = r["verdict"]
        for (i_a, i_r, w, tau_c), verdicts in configs.items():
            row = "".join("S" if verdicts.get(x) == "stable" else "u" for x in ratios)
            first = next((x for x in ratios if verdicts.get(x) == "stable"), math.nan)
            print(
                f"({i_a:.4g}, {i_r:.4g}, {w:.4g}, {tau_c:.3g})".ljust(60) + f" {row}   {first:>8.3g}"
                f"   {float(min_static_ratio(tau_c, i_r, w)):>8.3g}"
            )
    _write_json(args.json, res)
    return 0


def print_fig5_12(results: list[dict]) -> None:
    """Rows by spin parameter k (q = k + 1), columns by tau_S / tau_C: S/u on the PFR (anti-phase,
    phi > 0) branch Fig. 5.12 covers, s/x (stable/unstable) where the cone is in phase (phi < 0)."""
    ratios = sorted({r["ratio"] for r in results})
    print(
        f"Fig. 5.12 map: rows k (q = k + 1), columns tau_S/tau_C {ratios[0]:g}..{ratios[-1]:g}; "
        "S/u stable/unstable in anti-phase (PFR), s/x in phase"
    )
    rows: dict = {}
    for r in results:
        stable = r["verdict"] == "stable"
        mark = ("S" if stable else "u") if r["phi_rad"] > 0 else ("s" if stable else "x")
        rows.setdefault(r["spin_k"], {})[r["ratio"]] = mark
    for k in sorted(rows, reverse=True):
        print(f"  k = {k:+6.3f} (q = {k + 1:+6.3f})  " + "".join(rows[k].get(x, " ") for x in ratios))


def _write_json(path: str | None, res) -> None:
    from labkit.cli.output import write_json

    write_json({"points": res.results, "computed": res.computed, "reused": res.reused}, path, "sweep")
