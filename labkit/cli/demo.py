"""``labkit demo``: the Fig. 5.25 speed sweep on the emulated rig, on a virtual clock.

Runs the bundled ``emulated-fig525`` rig (motor, tachometer and balance emulated on one
model plant: the balance force is the PFR the model derives from the rig's magnets and
geometry, with seeded imperfections; docs/explanation/twin.md) through ``speed-sweep``, saves the session
and prints which plant ran, the measured force against the model's, the fitted exponent and
how to look at it.
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
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.protocols.launch import execute, prepare_run
from labkit.rig import bundled_rig_path
from labkit.stream import parse_rerun_spec


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help=COMMAND_SUMMARIES["demo"],
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
    model_b = print_measured_vs_model(prep.rig, outcome.results.get("points") or [])
    if b:
        print(
            f"fitted power law y = a x^b: b = {b['value']:.3f} +/- {b['stderr']:.3f} "
            f"({model_b}; paper Fig. 5.25: -1.9)"
        )
    rrd = outcome.session / "run.rrd"
    if rrd.exists():
        print(f"viewer: rerun {rrd}")
    else:
        print(f"viewer: the run was streamed to --rerun {rerun_text(args.rerun)} (no run.rrd)")
    print(f"replay offline: labkit replay {outcome.session}")
    return 0


def plant_of(rig: Any) -> str:
    """The plant preset the rig's emulated devices share (``plant=`` of their sim:// URLs)."""
    from labkit.emulators.urls import parse_sim_url
    names = {parse_sim_url(d.port).plant for d in rig.devices.values() if d.port.startswith("sim://")}
    return ", ".join(sorted(names)) or "none"


def print_measured_vs_model(rig: Any, points: list[dict]) -> str:
    """Print which plant ran and, for a model plant, measured force against the model's;
    returns the model's (or the fitted law's) exponent as text for the fit line."""
    plant = plant_of(rig)
    if not plant.startswith("model-"):
        print(f"plant: {plant} (the paper's fitted law y = 224e6 x^-1.9 typed in)")
        return "emulator: -1.9"
    from labkit.emulators.twin_model import force_g, params_from_rig
    from labkit.protocols.quickfit import quick_fit_power_law
    params = params_from_rig(rig)
    print(f"plant: {plant} (model of the rig's magnets: m_R m_F = {params.moment_product:.3g} A^2 m^4, "
          f"gap {params.gap_m * 1e3:g} mm; docs/explanation/twin.md)")
    rows = [(p["speed_rpm"], p["speed_rad_s"], p["force_g"]) for p in points if p.get("force_g")]
    print("  speed_rpm  measured_g   model_g   diff")
    model = []
    for rpm, w, meas in rows:
        m = force_g(params, w)
        model.append(m)
        print(f"  {rpm:9.0f}  {meas:10.4f}  {m:8.4f}  {(meas / m - 1) * 100:+5.2f} %")
    if len(rows) < 3:
        return "model: n/a"
    fit = quick_fit_power_law([r[0] for r in rows], model)
    return f"model at these speeds: {fit['params']['b']['value']:.3f}"
