"""``labkit predict [RIG]``: predict a rotator / floator pair before building it.

Does the floator bind beneath the rotator at this speed (point dipoles, gravity included), at
what distance, how stiff, with what cone angle, is it stable, between which speeds does the
bound state exist, and how does the speed scale to other floator masses (Eq. 6.18)? Every number
says how it was obtained, its estimated accuracy and its cost; a short ``labkit.sim`` run from
the predicted equilibrium checks it (``--no-verify`` skips that).

Magnets come from a rig file's [bodies.rotator] / [bodies.floator] or from options:

  labkit predict --rotator cylinder:6x3mm --floator sphere:10mm --speed-rpm 25000 --tilt-deg 5
  labkit predict my-rig.toml --speed-rpm 12000
  labkit predict --rotator cylinder:6x3mm --floator sphere:10mm --tilt-deg 5 \\
      --map tilt_deg=2:8:n=7 speed_rpm=10000:40000:n=7 --out map.jsonl [--scheduler tcp://host:8786]
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING

from labkit.cli.confirm import CONFIRM_POINTS, add_yes_argument, confirm_size
from labkit.cli.output import add_json_argument, note_first_compile, write_json
from labkit.cli.predict_inputs import (
    PredictInputError,
    check_remanence,
    magnet_option,
    magnets_from_rig,
)
from labkit.cli.progress import ProgressLines
from labkit.cli.summaries import COMMAND_SUMMARIES

if TYPE_CHECKING:  # the modules behind these import scipy and numba: loaded when a command runs
    from labkit.predict.estimate import Estimate
    from labkit.predict.pair import Pair
    from labkit.predict.predictor import Prediction

ORDER = ("bound", "r_eq_mm", "axial_stiffness_N_m", "axial_stiffness_sim_N_m", "lateral_stiffness_N_m",
         "cone_angle_deg", "cone_angle_steady_deg", "lateral_circle_mm", "pfr_force_N", "attraction_N",
         "max_load_N", "eq5_46_ratio", "growth_rate_1_s", "min_speed_rpm", "max_speed_rpm",
         "scaling_exponent", "sim_bound", "sim_r_mean_mm")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("predict", help=COMMAND_SUMMARIES["predict"],
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("rig", nargs="?", help="rig file (only its [bodies] are read) or bundled rig name")
    p.add_argument("--rotator", metavar="SPEC",
                   help="rotator magnet, e.g. cylinder:6x3mm (diameter x length)")
    p.add_argument("--floator", metavar="SPEC", help="floator magnet, e.g. sphere:10mm, block:10x5x2mm")
    p.add_argument("--speed-rpm", type=float, help="rotator speed (rpm)")
    p.add_argument("--tilt-deg", type=float,
                   help="rotator dipole tilt gamma (deg; default: the rig's, else 5)")
    p.add_argument("--grade", help="NdFeB grade for magnets without a moment (default N42)")
    p.add_argument("--remanence-t", type=float, help="remanence B_r (T) instead of --grade")
    p.add_argument("--above", action="store_true", help="floator above the rotator (default: beneath)")
    p.add_argument("--no-verify", action="store_true", help="skip the time-domain check")
    p.add_argument("--no-limits", action="store_true",
                   help="skip the speed limits and the Eq. 6.18 scaling (the slowest part, a few s)")
    p.add_argument("--verify-cycles", type=int, default=2000,
                   help="drive periods of the check (default 2000)")
    add_json_argument(p, "the prediction (or the map)")
    p.add_argument("--map", nargs="+", metavar="AXIS=START:STOP:n=COUNT",
                   help="stability map over tilt_deg and/or speed_rpm")
    p.add_argument("--out", metavar="STORE", help="map: JSON-lines store, resumed when it exists")
    p.add_argument("--workers", type=int, default=1, help="map: local worker processes (default 1)")
    p.add_argument("--scheduler", metavar="ADDR", help="map: Dask scheduler, e.g. tcp://host:8786")
    p.add_argument("--chunk", type=int, default=4, help="map: points per task (default 4)")
    p.add_argument("--map-verify", type=int, default=0, metavar="CYCLES",
                   help="map: also run the time-domain check (CYCLES drive periods) at every bound point")
    add_yes_argument(p, f"the map has more than {CONFIRM_POINTS} points")
    p.set_defaults(func=run)


def _pair(args: argparse.Namespace) -> Pair:
    from labkit.predict.pair import Pair

    remanence = check_remanence(args.remanence_t, args.grade)
    grade = args.grade or ""
    rotator = floator = None
    tilt = None
    if args.rig:
        rotator, floator, tilt = magnets_from_rig(args.rig, remanence)
        if tilt == 0.0:
            tilt = None
    if args.rotator:
        rotator = magnet_option("--rotator", args.rotator, args.remanence_t, grade)
    if args.floator:
        floator = magnet_option("--floator", args.floator, args.remanence_t, grade)
    if rotator is None or floator is None:
        missing = " and ".join(o for o, m in (("--rotator", rotator), ("--floator", floator)) if m is None)
        raise PredictInputError(f"{missing} missing: give a rig file or both magnets")
    if args.tilt_deg is not None:
        if not math.isfinite(args.tilt_deg) or abs(args.tilt_deg) >= 90:
            raise PredictInputError(f"--tilt-deg: must be below 90 degrees, got {args.tilt_deg}")
        tilt = math.radians(args.tilt_deg)
    elif tilt is None:
        tilt = math.radians(5.0)
    return Pair(rotator, floator, tilt, "above" if args.above else "beneath")


def run(args: argparse.Namespace) -> int:
    from labkit.predict.predictor import RPM, predict

    pair = _pair(args)
    if args.speed_rpm is not None and not (math.isfinite(args.speed_rpm) and args.speed_rpm > 0):
        raise PredictInputError(f"--speed-rpm: must be positive, got {args.speed_rpm}")
    if args.verify_cycles < 10:
        raise PredictInputError(f"--verify-cycles: at least 10, got {args.verify_cycles}")
    if args.map:
        return _run_map(args, pair)
    if args.speed_rpm is None:
        raise PredictInputError("--speed-rpm missing (the rotator speed to predict at)")
    from labkit.predict.pair import check_speed_can_bind

    check_speed_can_bind(pair, args.speed_rpm / RPM, RPM)  # a speed far too low: refused at once
    steps = ["bound state, stiffness and stability"] + ([] if args.no_limits else ["speed limits"]) + (
        [] if args.no_verify else [f"a {args.verify_cycles}-cycle simulation check"])
    print(f"labkit predict: computing {', '.join(steps)}...", file=sys.stderr, flush=True)
    if not args.no_verify:
        note_first_compile("predict")
    pred = predict(pair, args.speed_rpm / RPM, run_verify=not args.no_verify,
                   verify_cycles=args.verify_cycles, speed_limits=not args.no_limits,
                   scaling=not args.no_limits,
                   on_stage=ProgressLines("labkit predict", "").say)  # lines only after 2 s
    print(format_prediction(pred))
    if args.json:
        _write_json(args.json, pred.to_json())
    return 0


def _write_json(path: str, data) -> None:
    write_json(data, path, "predict")  # labkit.cli.output: '-' is stdout, alone


def _jsonable(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    try:
        return float(x)
    except (TypeError, ValueError):
        return str(x)


def _fmt_value(e: Estimate) -> str:
    v = e.value
    if isinstance(v, bool):
        return "yes" if v else "no"
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.5g} {e.unit}".strip()


def _fmt_acc(e: Estimate) -> str:
    if e.accuracy is None or not math.isfinite(e.accuracy):
        return ""
    return f"±{e.accuracy:.2g}"


def format_prediction(pred: Prediction) -> str:
    """The table printed by ``labkit predict``."""
    inp = pred.inputs
    lines = []
    for name in ("rotator", "floator"):
        m = inp[name]
        sizes = "x".join(f"{s:g}" for s in m["sizes_mm"])
        lines.append(f"{name:8} {m['shape']} {sizes} mm, {m['mass_g']:.4g} g, "
                     f"m = {m['moment_a_m2']:.4g} A m^2, "
                     f"I_A {m['inertia_axial_kg_m2']:.3g} / I_R {m['inertia_radial_kg_m2']:.3g} kg m^2 "
                     f"({m['source']})")
    lines.append(f"setting  {inp['speed_rpm']:.0f} rpm, tilt {inp['tilt_deg']:.3g} deg, "
                 f"floator {inp['placement']} "
                 f"the rotator, contact at {inp['contact_distance_mm']:.3g} mm")
    lines.append("")
    rows = [("quantity", "value", "accuracy", "method", "eq.", "cost")]
    keys = [k for k in ORDER if k in pred.estimates] + [k for k in pred.estimates if k not in ORDER]
    for k in keys:
        e = pred.estimates[k]
        rows.append((e.label, _fmt_value(e), _fmt_acc(e), e.method, e.equation,
                     f"{e.cost_s:.2f} s" if e.cost_s >= 0.005 else ""))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    for r in rows:
        lines.append("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip())
    notes = [(pred.estimates[k].label, pred.estimates[k].note) for k in keys if pred.estimates[k].note]
    if notes:
        lines.append("")
        lines.extend(f"  {label}: {note}" for label, note in notes)
    if pred.scaling:
        lines.append("")
        lines.append("Eq. 6.18 scaling of the minimum speed to similar floators:")
        for row in pred.scaling:
            local = row.get("local_power_law_rpm")
            lines.append(f"  {row['mass_g']:9.4g} g  {row['eq6_18_min_speed_rpm']:8.0f} rpm (m^-1/3)"
                         + (f"  {local:8.0f} rpm (local exponent)" if local is not None else ""))
    for w in pred.warnings:
        lines.append(f"WARNING  {w}")
    lines.append(f"verdict  {pred.verdict}  (total {pred.cost_s:.1f} s)")
    return "\n".join(lines)


def _run_map(args: argparse.Namespace, pair: Pair) -> int:
    from labkit.numerics.sweep import run_sweep
    from labkit.predict.stability_map import (
        MapSpecError,
        evaluate_points,
        grid_points,
        parse_axis,
        render_map,
    )

    try:
        axes = dict(parse_axis(a) for a in args.map)
        points = grid_points(axes, pair, args.speed_rpm, args.map_verify)
    except MapSpecError as exc:
        raise PredictInputError(f"--map: {exc}") from None
    confirm_size(len(points), CONFIRM_POINTS, "map points", yes=args.yes, command="predict")
    result = run_sweep(points, evaluate_points, store=args.out, chunk=args.chunk, workers=args.workers,
                       scheduler=args.scheduler, progress=sys.stderr.isatty(), description="predict map")
    rows = [{k: v for k, v in r.items() if k not in ("rotator", "floator")} for r in result.results]
    print(render_map(rows))
    cost = sum(r.get("wall_s") or 0.0 for r in rows)
    print(f"{len(rows)} points: {result.computed} computed, {result.reused} reused from "
          f"{args.out or 'nothing'}; {cost:.1f} s of evaluation")
    if args.json:
        _write_json(args.json, {"schema": "labkit.predict.map/1", "inputs": {
            "rotator": pair.rotator.to_json(), "floator": pair.floator.to_json(),
            "placement": pair.placement},
            "points": rows})
    return 0
