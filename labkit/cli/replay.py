"""``labkit replay SESSION``: re-run a session's protocol against its own serial cassettes.

Three levels (docs/explanation/replay.md): **exact** for a session recorded on the virtual clock (what
the drivers send must match the recording byte for byte; results identical), **faithful**
for one recorded on the real clock (device bytes at their recorded times, writes matched by
content; the same decisions and the points within tolerance), chosen from run.json's clock,
and **analysis only** (``--analysis-only``: the recorded bytes re-parsed into readings,
points and fit; no protocol run). Any difference is printed and the exit status is 1.
``--export-csv`` instead writes ``readings/*.csv``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from labkit.cli.output import add_json_argument, announce_rerun_file, write_json
from labkit.cli.run import close_sinks
from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.protocols.events import FlagTally
from labkit.protocols.replay import LEVEL_WORDS, LEVELS, replay_session
from labkit.session import export_csv, load_session_record
from labkit.stream import add_rerun_argument


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replay",
        help=COMMAND_SUMMARIES["replay"],
        description=__doc__.split("\n\n")[1] if __doc__ else None,
    )
    p.add_argument("session", help="session directory")
    p.add_argument("--export-csv", action="store_true", help="only export readings/*.jsonl to CSV")
    p.add_argument("--level", choices=LEVELS, default="auto",
                   help="exact, faithful or analysis (default auto: exact for a virtual-clock session, "
                        "faithful for a real-clock one)")
    p.add_argument("--analysis-only", dest="level", action="store_const", const="analysis",
                   help="no protocol run: re-parse the recorded bytes into readings, points and fit "
                        "(any session, also from an older labkit)")
    add_json_argument(p, "the comparison (identical, differences, status, results)")
    add_rerun_argument(p)
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    from labkit.stream import run_sink

    if args.export_csv:
        record = load_session_record(args.session)
        problems: list[str] = []
        for path in export_csv(record.path, problems):
            print(path)
        for warning in problems:
            print(f"labkit replay: warning: {warning}", file=sys.stderr)
        return 0
    flags = FlagTally()
    sinks: list = [flags]
    if args.rerun is not None:  # the same rerun sink as `labkit run`
        sinks.append(run_sink(args.rerun, None))
    try:
        result = replay_session(Path(args.session), sinks=sinks, level=args.level)
    finally:
        close_sinks(sinks, "replay")
    announce_rerun_file(args.rerun, "replay")
    for warning in result.warnings:
        print(f"labkit replay: warning: {warning}", file=sys.stderr)
    out = result.outcome
    write_json({"session": str(args.session), "level": result.level, "identical": result.identical,
                "differences": result.differences, "status": out.status, "reason": out.reason,
                "warnings": result.warnings, "ports": result.ports, "timing": result.timing,
                "analysis_note": result.analysis_note,
                "results": out.results},
               args.json, "replay")
    print(f"replay level: {LEVEL_WORDS[result.level]}")
    if flags.counts:
        print(f"device flags: {flags.summary()}")
    if out.status != "completed" and out.error is not None and result.recorded is None:
        print(f"labkit replay: {out.status}: {out.reason}", file=sys.stderr)
        return 2
    if result.analysis_note:  # a session made by another version of its image analysis
        print(result.analysis_note)
    if result.identical:
        print(success_line(args.session, result))
        for port in result.ports:
            print(f"  {port_line(port)}")
        if any(result.timing.values()):
            print(f"  {timing_line(result.timing)}")
        return 0
    print(f"labkit replay: the replay of {args.session} differs from the recording:", file=sys.stderr)
    for line in result.differences[:20]:
        print(f"  {line}", file=sys.stderr)
    if out.status != "completed" and not any("diverged" in d for d in result.differences):
        print(f"  the replayed run ended {out.status}: {out.reason}", file=sys.stderr)
    if result.level != "analysis":
        print(f"  (the numbers alone: labkit replay --analysis-only {args.session})", file=sys.stderr)
    return 1


def success_line(session: str, result) -> str:
    """One line saying what the replay reproduced, in the level's own terms."""
    n = len((result.outcome.results or {}).get("points", []))
    ended = [d for d in result.decisions if d["decision"] in ("interlock", "fault")]
    how = f"; {ended[0]['decision']} in step {ended[0]['step'] + 1} as recorded" if ended else ""
    if result.level == "exact" and result.analysis_note:
        return (f"replayed {session}: {n} points, results as in results.json (every byte and decision as "
                f"recorded; image-analysis numbers within the analysis's stated accuracy){how}")
    if result.level == "exact":
        return (f"replayed {session}: {n} points, results identical to results.json "
                f"(points exact; fits and image-analysis numbers within relative 1e-6){how}")
    if result.level == "analysis" and not result.recomputed:
        return (f"re-analysed {session}: {n} points taken as recorded (the warning above says why), the fit "
                "recomputed from them within tolerance of results.json")
    if result.level == "analysis":
        return (f"re-analysed {session}: {n} points and the fit recomputed from the recorded bytes, "
                "within tolerance of results.json (measured values 0.5 %)")
    steps = sum(1 for d in result.decisions if d["decision"] == "step")
    images = "image analyses within their stated accuracy" if result.analysis_note else "image analyses 1e-6"
    return (f"replayed {session}: {n} points within tolerance of results.json (measured values 0.5 %, "
            f"{images}), the same decisions in {steps} steps{how}")


def port_line(port: dict) -> str:
    if "frames_recorded" in port:  # a camera's frame cassette (labkit.devices.camera.faithful)
        text = (f"{port['port']}: {port['frames_served']} of {port['frames_recorded']} recorded frames "
                f"served in {port['bursts']} bursts at their recorded times")
        if port.get("failed_bursts"):
            text += f", {port['failed_bursts']} failed as the recorded camera failed it"
        if port.get("served_late"):
            text += f", {port['served_late']} later (at most {port['latest_s'] * 1e3:.0f} ms)"
        return text
    text = (f"{port['port']}: {port['identical']} of {port['recorded_writes']} recorded writes sent again "
            "as recorded")
    if port.get("near"):
        text += f", {port['near']} with another value"
    if port.get("repeats"):
        text += f", {port['repeats']} polls repeated"
    if port.get("held_up"):
        text += f", {port['held_up']} held up as in the recording"
    if port.get("not_repeated"):
        text += f", {port['not_repeated']} not sent again (keep-alives and polls)"
    return text


def timing_line(timing: dict) -> str:
    """What of the recording's timing (``clock.jsonl``) the faithful replay repeated."""
    return (f"timing as recorded: the protocol stood still {timing.get('stood_still', 0)} times outside a "
            f"sleep, {timing.get('delivered_late', 0)} tachometer reads were handed over late")
