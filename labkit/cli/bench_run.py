"""``labkit bench run``: how much faster than real time protocols run on the virtual clock.

Runs the Fig. 5.25 speed sweep on the emulated rig (no session written) and replays a
recorded session, and prints simulated seconds, wall seconds and their ratio for each.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from labkit.protocols import ListSink
from labkit.protocols.launch import execute, prepare_run
from labkit.protocols.replay import replay_session
from labkit.rig import bundled_rig_path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="protocol run and replay speed on the virtual clock (ratio to real time)")
    p.add_argument("--speeds", default="6000:20000:2000", help="speeds_rpm of the sweep")
    p.add_argument("--session", help="a recorded session to replay (default: none)")
    p.set_defaults(func=main)


def _simulated_seconds(sink: ListSink) -> float:
    return max((e.get("t", 0.0) for e in sink.events), default=0.0)


def main(args: argparse.Namespace) -> int:
    sink = ListSink()
    prep = prepare_run(str(bundled_rig_path("emulated-fig525")), "speed-sweep",
                       [f"speeds_rpm={args.speeds}"], session_root=None, sinks=[sink])
    start = time.perf_counter()
    outcome = execute(prep, None)
    wall = time.perf_counter() - start
    sim = _simulated_seconds(sink)
    print(f"speed-sweep on emulated-fig525: {sim:.1f} s simulated in {wall:.2f} s wall "
          f"= {sim / wall:.1f}x real time ({outcome.status})")
    if args.session:
        sink = ListSink()
        start = time.perf_counter()
        result = replay_session(Path(args.session), sinks=[sink])
        wall = time.perf_counter() - start
        sim = _simulated_seconds(sink)
        verdict = "identical" if result.identical else "DIFFERENT"
        print(f"replay of {args.session}: {sim:.1f} s recorded in {wall:.2f} s wall "
              f"= {sim / wall:.1f}x real time ({verdict} results)")
    return 0
