"""``labkit demo``: the Fig. 5.25 speed sweep on the emulated rig, on a virtual clock.

Runs the bundled ``emulated-fig525`` rig (motor, tachometer and balance emulated on one
plant whose balance force follows the paper's y = 224e6 x^-1.9) through ``speed-sweep``,
saves the session and prints where it is, the fitted exponent and how to look at it.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from labkit.cli.run import (
    add_common,
    add_set_argument,
    close_sinks,
    rerun_text,
    sinks_for,
    stream_session_to_rerun,
)
from labkit.protocols.launch import execute, prepare_run
from labkit.rig import bundled_rig_path
from labkit.stream import parse_rerun_spec


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="run the Fig. 5.25 sweep on the emulated rig (about 10 s)",
        description=__doc__.split("\n\n")[1] if __doc__ else None,
    )
    add_set_argument(p, "speed-sweep parameter, e.g. speeds_rpm=6000:20000:2000")
    add_common(p)
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    rig = bundled_rig_path("emulated-fig525")
    prep = prepare_run(
        str(rig),
        "speed-sweep",
        args.sets,
        clock=args.clock,
        session_root=args.sessions,
        sinks=sinks_for(args),
    )
    print(
        f"labkit demo: speed-sweep on {prep.rig.name} ({len(prep.runner.steps)} speeds, "
        f"{'virtual' if prep.clock.is_virtual else 'real'} clock)"
    )

    def on_session(runner: Any, session: Any) -> None:
        if args.rerun is None:  # the demo always saves SESSION/run.rrd
            args.rerun = parse_rerun_spec(f"save:{session.path / 'run.rrd'}")
        stream_session_to_rerun(args, runner, session, sinks)

    sinks: list[Any] = []
    try:
        outcome = execute(prep, args.sessions, notes=args.notes or "labkit demo", on_session=on_session)
    finally:
        close_sinks(sinks, "demo")
    if outcome.status != "completed":
        print(f"labkit demo: {outcome.status}: {outcome.reason}", file=sys.stderr)
        return 3 if outcome.stop_failed else 130 if outcome.status == "interrupted" else 2
    fit = outcome.results["fit"]
    b = fit.get("params", {}).get("b")
    print(f"session: {outcome.session}")
    for name in ("results.json", "events.jsonl", "readings", "cassettes"):
        print(f"  {outcome.session / name}")
    if b:
        print(
            f"fitted power law y = a x^b: b = {b['value']:.3f} +/- {b['stderr']:.3f} "
            "(emulator: -1.9; paper Fig. 5.25: -1.9)"
        )
    rrd = outcome.session / "run.rrd"
    if rrd.exists():
        print(f"viewer: rerun {rrd}")
    else:
        print(f"viewer: the run was streamed to --rerun {rerun_text(args.rerun)} (no run.rrd)")
    print(f"replay offline: labkit replay {outcome.session}")
    return 0
