"""``labkit run RIG PROTOCOL``: run a measurement protocol into a session directory.

Checks everything first (rig file, protocol, parameters, the rig's speed limit, that the
session folder is writable) and prints one line and exits 2 on a problem, before any motor
turns. ``--dry-run`` prints the plan and stops. Ctrl-C once: motors to zero, the run stops
at the next checkpoint and can be resumed; twice: safe state at once.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from labkit.cli.confirm import CONFIRM_STEPS, add_yes_argument, confirm_size
from labkit.cli.output import add_json_argument, announce_rerun_file, write_json
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import LabkitError
from labkit.protocols import PROTOCOLS, ProgressSink
from labkit.protocols.events import FlagTally
from labkit.protocols.launch import execute, prepare_run
from labkit.stream import add_rerun_argument

#: exit status when a STOP could not be delivered to a motor controller (docs/explanation/safety.md)
EXIT_STOP_FAILED = 3


def add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--sessions",
        default="sessions",
        metavar="DIR",
        help="folder for session directories (default: ./sessions)",
    )
    p.add_argument(
        "--clock",
        choices=("auto", "real", "virtual"),
        default="auto",
        help="auto (default): virtual when every device is emulated (sim://), else real",
    )
    p.add_argument("--notes", default="", help="operator notes stored in run.json")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_json_argument(p, "the outcome (status, session, points and fit)")
    add_yes_argument(p, f"the plan has more than {CONFIRM_STEPS} steps")
    add_rerun_argument(p)


def add_set_argument(p: argparse.ArgumentParser, help: str) -> None:
    """The repeatable ``--set KEY=VALUE`` protocol parameter (collected in ``args.sets``)."""
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE", help=help)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "run",
        help=COMMAND_SUMMARIES["run"],
        description=__doc__.split("\n\n")[1] if __doc__ else None,
    )
    p.add_argument("rig", nargs="?", help="rig file (rigs/*.toml) or a bundled rig name")
    p.add_argument("protocol", nargs="?", help=f"one of: {', '.join(sorted(PROTOCOLS))}")
    add_set_argument(p, "protocol parameter, e.g. speeds_rpm=6000:20000:1000 (repeatable)")
    p.add_argument(
        "--dry-run", action="store_true", help="print the planned steps and check limits; no motion"
    )
    p.add_argument("--resume", metavar="SESSION", help="continue the remaining steps of SESSION as a new run")
    p.add_argument("--rig", dest="resume_rig", metavar="FILE",
                   help="with --resume: use FILE instead of the session's rig copy (ports and serial "
                        "settings may differ; bodies, limits, control and devices must not)")
    add_common(p)
    p.set_defaults(func=main)


def rerun_text(spec: Any) -> str | None:
    """``save:FILE`` / ``connect:ADDR`` / ``spawn`` as typed, for run.json."""
    if spec is None:
        return None
    mode, target = getattr(spec, "mode", str(spec)), getattr(spec, "target", "")
    return f"{mode}:{target}" if target else str(mode)


def sinks_for(args: argparse.Namespace) -> list[Any]:
    sinks: list[Any] = [FlagTally()]
    if not args.no_progress:
        sinks.append(ProgressSink())
    return sinks


def warn_flags(sinks: list[Any]) -> None:
    """One line on stderr when a device reading carried a flag that means its value may be wrong."""
    for sink in sinks:
        text = sink.summary(suspect_only=True) if isinstance(sink, FlagTally) else ""
        if text:
            print(f"labkit run: warning: readings flagged {text} may be wrong; see the report's "
                  "Device flags (labkit report SESSION)", file=sys.stderr)


def attach_rerun(args: argparse.Namespace, runner: Any, session_path: Any) -> Any:
    """Add the rerun sink (``labkit.stream.run_sink``) for ``args.rerun`` to the run's event bus.

    The blueprint gets one speed view per control loop and one view per balance/tachometer
    role of the rig, so a two-tachometer rig shows the floator spin beside the rotor speed.
    """
    spec = getattr(args, "rerun", None)
    if spec is None:
        return None
    from labkit.stream import run_sink

    rig = runner.rig
    loops = [loop.name for loop in rig.control.loops]
    loop_tachs = {loop.tach for loop in rig.control.loops}
    devices = [role for role, dev in rig.devices.items()
               if dev.kind == "balance" or (dev.kind == "tachometer" and role not in loop_tachs)]
    sink = run_sink(spec, session_path, loops=loops or None, devices=devices or None)
    runner.bus.add(sink)
    return sink


def stream_session_to_rerun(args: argparse.Namespace, runner: Any, session: Any, sinks: list[Any]) -> None:
    """Once the session exists: note ``args.rerun`` in run.json and attach its sink to the run
    (appended to ``sinks``, which the caller closes with :func:`close_sinks`)."""
    session.update_meta(rerun=rerun_text(args.rerun))
    sink = attach_rerun(args, runner, session.path)
    if sink is not None:
        sinks.append(sink)


def close_sinks(sinks: list[Any], command: str) -> None:
    """Close live sinks (rerun) at the end of a run; a viewer that was never reached is one
    line on stderr, never a hang or a traceback (the session on disk is complete)."""
    for sink in sinks:
        close = getattr(sink, "close", None)
        if callable(close):
            close()
        problem = getattr(sink, "flush_error", None)
        if problem:
            print(f"labkit {command}: rerun viewer not reached, live view incomplete ({problem})",
                  file=sys.stderr)


def outcome_json(outcome: Any) -> dict[str, Any]:
    """The ``--json`` document of a run: ``{"status", "reason", "session", "results"}``."""
    return {"status": outcome.status, "reason": outcome.reason,
            "session": str(outcome.session) if outcome.session else None,
            "results": outcome.results}


def warn_points(results: dict[str, Any] | None) -> None:
    """One line on stderr per warning a point carries (``warnings``: e.g. the balance's drift)."""
    for point in (results or {}).get("points", []):
        for warning in point.get("warnings") or []:
            print(f"labkit run: warning: step {int(point.get('step', -1)) + 1}: {warning}", file=sys.stderr)


def report(outcome: Any) -> int:
    where = f" (session {outcome.session})" if outcome.session else ""
    warn_points(outcome.results)
    fit = (outcome.results or {}).get("fit") or {}
    params = ", ".join(
        f"{k} = {v['value']:.4g} +/- {v['stderr']:.2g}"
        for k, v in fit.get("params", {}).items()
        if v.get("stderr") is not None
    )
    if outcome.status == "completed":
        print(f"completed {len((outcome.results or {}).get('points', []))} points{where}")
        if params:
            from labkit.protocols.quickfit import quick_fit_label
            print(f"quick fit ({quick_fit_label(str(fit.get('model')))}): {params}")
        return 0
    print(f"labkit run: {outcome.status}: {outcome.reason}{where}", file=sys.stderr)
    if getattr(outcome, "stop_failed", None):
        return EXIT_STOP_FAILED  # no resume hint: the rotor may still be turning
    if outcome.session and outcome.session.is_dir():  # a deleted session has nothing to resume
        print(f"resume with: labkit run --resume {outcome.session}", file=sys.stderr)
    return 130 if outcome.status == "interrupted" else 2


def check_ports_free(rig: Any) -> None:
    """Refuse (PortBusy: "port busy, held by PID N") before a session exists when another
    process holds one of the rig's serial devices (labkit.io.port_lock)."""
    from labkit.io.port_lock import check_free

    for device in rig.devices.values():
        check_free(device.port)


def main(args: argparse.Namespace) -> int:
    if args.resume_rig and not args.resume:
        raise LabkitError("--rig FILE goes with --resume SESSION (a new run names its rig first)")
    if args.resume and args.rig and args.resume_rig:
        raise LabkitError("--resume: give the replacement rig once (--rig FILE)")
    prep = prepare_run(
        args.resume_rig or args.rig if args.resume else args.rig,
        args.protocol,
        args.sets,
        clock=args.clock,
        session_root=None if args.dry_run else args.sessions,
        resume=args.resume,
        sinks=[] if args.dry_run else sinks_for(args),
    )
    for warning in prep.warnings:
        print(f"labkit run: warning: {warning}", file=sys.stderr)
    if args.dry_run:
        print(prep.runner.dry_run())
        write_json({"status": "dry-run", "protocol": prep.protocol.name, "params": prep.params,
                    "n_steps": len(prep.runner.steps), "plan": prep.runner.dry_run()},
                   getattr(args, "json", None), "run")
        return 0
    confirm_size(len(prep.runner.steps) - len(prep.runner.done_steps), CONFIRM_STEPS, "measurement steps",
                 yes=getattr(args, "yes", False), command="run")
    check_ports_free(prep.rig)
    from labkit.control.supervisor import needs_supervisor, supervised

    if needs_supervisor(prep.rig):  # real motor ports: a supervisor stops them if this run dies
        return supervised(prep.rig, lambda: run_prepared(args, prep), sessions=args.sessions)
    return run_prepared(args, prep)


def run_prepared(args: argparse.Namespace, prep: Any) -> int:
    """Execute a prepared run into a session and report it (the worker, when supervised)."""
    sinks: list[Any] = []

    def on_session(runner: Any, session: Any) -> None:
        stream_session_to_rerun(args, runner, session, sinks)

    try:
        outcome = execute(prep, args.sessions, notes=args.notes, on_session=on_session)
    finally:
        close_sinks(sinks, "run")
    announce_rerun_file(args.rerun, "run")
    warn_flags(prep.runner.bus.sinks)
    write_json(outcome_json(outcome), getattr(args, "json", None), "run")
    return report(outcome)
