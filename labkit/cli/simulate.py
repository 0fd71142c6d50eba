"""``labkit simulate SCENE``: run a scene and print its status, invariant and quantities of interest.

``SCENE`` is a TOML file or the name of a bundled scene (``labkit simulate --list``).
``--rerun SPEC`` is stored in the result (``spec.rerun``) and handed to a streaming sink if one
is installed (``labkit.stream.sim_sink.stream_result(result, spec)``); ``labkit.sim`` itself
never streams or prints.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys

from labkit.cli.numbers import number
from labkit.cli.output import add_json_argument, note_first_compile, write_json
from labkit.cli.parsers import command_parser
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.sim.integrators import DEFAULT_INTEGRATOR, INTEGRATORS

SINK_MODULE = "labkit.stream.sim_sink"


def register(sub: argparse._SubParsersAction) -> None:
    p = command_parser(sub, "simulate", COMMAND_SUMMARIES["simulate"], __doc__)
    p.add_argument("scene", nargs="?", help="scene TOML file or bundled scene name")
    p.add_argument(
        "--cycles", type=number(0, low_open=True), default=None,
        help="drive periods to simulate (default: the scene's)"
    )
    p.add_argument(
        "--integrator",
        default=DEFAULT_INTEGRATOR,
        choices=INTEGRATORS,
        help=f"integrator (default {DEFAULT_INTEGRATOR})",
    )
    p.add_argument(
        "--steps-per-period",
        type=number(1, 10**7, integer=True),
        default=None,
        help="fixed steps per drive period for splittings (default: automatic)",
    )
    p.add_argument("--samples-per-period", type=number(1, 10**5, integer=True), default=8,
                   help="stored samples per period (default 8)")
    p.add_argument(
        "--decimate",
        type=int,
        default=1,
        metavar="K",
        help="store every K-th sample only (and the last): K times less memory for long runs; the "
        "invariant and quantities of interest are then taken on the stored samples",
    )
    p.add_argument(
        "--attitude",
        choices=["axis", "matrix"],
        default="axis",
        help="what to store of each body's attitude: 'axis' keeps an axisymmetric body's axis "
        "(3 numbers per sample) and any other body's rotation matrix; 'matrix' keeps every "
        "rotation matrix, also the turn of an axisymmetric body about its axis (default axis)",
    )
    p.add_argument(
        "--target-error",
        type=float,
        metavar="E",
        help="choose the splitting (order 4, 6 or 8) and steps per period that reach this stroboscopic "
        "error over the run, from short pilot runs (overrides --integrator and --steps-per-period)",
    )
    p.add_argument("--rtol", type=number(0, 1, low_open=True), default=1e-10,
                   help="relative tolerance of scipy references")
    p.add_argument(
        "--drift-threshold",
        type=number(0, low_open=True),
        default=1e-6,
        help="relative invariant drift that marks the run as failed (default 1e-6)",
    )
    add_json_argument(p, "the result summary")
    p.add_argument("--series", action="store_true", help="include the sampled series in --json")
    p.add_argument(
        "--rerun", metavar="SPEC", help="stream poses to rerun: spawn, connect[:ADDR] or save:FILE"
    )
    p.add_argument("--list", action="store_true", help="list bundled scenes and exit")
    p.add_argument("--compile-only", action="store_true", help="print what the scene compiles to and exit")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from labkit.sim import bundled_scenes, compile_scene, load_scene, simulate

    if args.list:
        for name in bundled_scenes():
            print(name)
        return 0
    if not args.scene:
        print("labkit simulate: give a SCENE (file or bundled name; --list shows them)", file=sys.stderr)
        return 2
    scene = load_scene(args.scene)
    system = compile_scene(scene)
    if args.compile_only:
        print(json.dumps(system.summary(), indent=2))
        return 0
    if args.integrator not in ("dop853", "lsoda", "radau"):  # the splittings run numba kernels
        note_first_compile("simulate")
    if args.target_error is not None:
        _choose(args, scene, system)
    settings = dict(integrator=args.integrator, steps_per_period=args.steps_per_period,
                    samples_per_period=args.samples_per_period, rtol=args.rtol,
                    drift_threshold=args.drift_threshold, system=system, decimate=args.decimate,
                    attitude=args.attitude)
    cycles = float(args.cycles if args.cycles is not None else scene.cycles)
    _announce_estimate(scene, cycles, settings)
    result = simulate(scene, cycles=args.cycles, **settings)
    if args.rerun:
        result.spec["rerun"] = args.rerun
        _stream(result, args.rerun)
    print(format_summary(result))
    if args.json:
        write_json(result.to_json(args.series), args.json, "simulate")
    return 0 if result.ok else 1


#: a run of at least this many drive periods is first timed on a pilot of 1 % of them (at most
#: PILOT_MAX_CYCLES), and its time announced when above ESTIMATE_SAY_S (the kernels run in one
#: call, so there is no progress to report from inside)
PILOT_FROM_CYCLES, PILOT_MAX_CYCLES, ESTIMATE_SAY_S = 1000.0, 1000.0, 5.0


def _announce_estimate(scene, cycles: float, settings: dict) -> None:
    """One stderr line with the run's estimated time from a pilot run, when it is long."""
    from labkit.sim import simulate

    if cycles < PILOT_FROM_CYCLES:
        return
    pilot_cycles = min(cycles / 100, PILOT_MAX_CYCLES)
    pilot = simulate(scene, cycles=pilot_cycles, **settings)
    estimate = pilot.wall_s * cycles / pilot_cycles
    if estimate > ESTIMATE_SAY_S:
        print(f"labkit simulate: {cycles:g} cycles will take about {_duration(estimate)} "
              f"(a {pilot_cycles:g}-cycle pilot took {pilot.wall_s:.2g} s)", file=sys.stderr, flush=True)


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min" if seconds < 7200 \
        else f"{seconds / 3600:.1f} h"


def _choose(args: argparse.Namespace, scene, system) -> None:
    """Set ``args.integrator`` and ``args.steps_per_period`` for ``--target-error``."""
    from labkit.numerics.checks import NumericsError
    from labkit.numerics.choose import choose

    target = args.target_error
    if not (math.isfinite(target) and 0 < target < 1):
        raise NumericsError(f"--target-error must be between 0 and 1, got {target:g}")
    cycles = float(args.cycles if args.cycles is not None else scene.cycles)
    choice = choose(scene, system, cycles, target, samples_per_period=args.samples_per_period)
    print(choice.line())
    args.integrator, args.steps_per_period = choice.integrator, choice.steps_per_period


def _stream(result, spec: str) -> None:
    try:
        sink = importlib.import_module(SINK_MODULE)
    except ModuleNotFoundError as exc:
        if exc.name != SINK_MODULE:
            raise
        print(
            f"labkit simulate: no rerun sink installed yet; spec {spec!r} stored in the result",
            file=sys.stderr,
        )
        return
    sink.stream_result(result, spec)


def _fmt(x) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.6g}" if isinstance(x, float) else str(x)


def format_summary(result) -> str:
    """Human-readable summary of a :class:`labkit.sim.SimResult`."""
    c = result.compile
    lines = [
        f"scene      {result.scene}  ({c['kind']}{', ' + c['equation'] if 'equation' in c else ''})",
        f"integrator {result.integrator}  {json.dumps(result.setting)}",
        f"horizon    {result.cycles:g} cycles of {result.period_s:.6g} s; {result.n_force_evals} force "
        f"evaluations in {result.wall_s:.3g} s",
        f"status     {result.status}{'  ' + result.status_detail if result.status_detail else ''}",
        f"invariant  {result.invariant}: max relative drift {_fmt(result.invariant_drift)}"
        + (
            f"; |dP| {_fmt(result.momentum_drift)}, |dJ| {_fmt(result.angular_momentum_drift)}"
            if result.momentum_drift is not None
            else ""
        ),
        f"rotation   max |R^T R - I| {_fmt(result.rotation_residual)}",
    ]
    for name, q in result.qoi.get("bodies", {}).items():
        if "cone_angle_rad" in q:
            ca = q["cone_angle_rad"]
            eq = q.get("cone_angle_closed_form_rad")
            lines.append(
                f"{name:10s} cone angle mean {ca['mean']:.6g} rad (min {ca['min']:.6g}, max {ca['max']:.6g})"
                + (f"; closed form (Eq. 5.35/5.64) {eq:.6g} rad" if eq is not None else "")
            )
        if "mean_force_N" in q:
            f = q["mean_force_N"]
            lines.append(f"{name:10s} mean magnetic force [{f[0]:.4g}, {f[1]:.4g}, {f[2]:.4g}] N")
    if "reduced" in result.qoi:
        r = result.qoi["reduced"]
        lines.append(
            f"reduced    {r['equation']}: angle mean {r['angle_mean_rad']:.6g} rad, "
            f"amplitude {r['angle_amplitude_rad']:.6g} rad"
        )
    if "distance_m" in result.qoi:
        d = result.qoi["distance_m"]
        lines.append(
            f"distance   mean {d['mean'] * 1e3:.6g} mm (min {d['min'] * 1e3:.6g}, max {d['max'] * 1e3:.6g})"
        )
    return "\n".join(lines)
