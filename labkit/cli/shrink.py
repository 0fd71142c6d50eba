"""``labkit shrink SESSION OUT``: a recorded session made small enough to commit as a CI fixture.

Copies SESSION to OUT, shrinks every frame cassette in it (``--every`` k-th frame of each burst,
``--crop X,Y,W,H``, ``--scale``, JPEG ``--quality``: :mod:`labkit.devices.camera.shrink`), adjusts
the run's parameters that depend on them (the protocol's ``shrunk_params``: ``cone-sweep`` takes
fewer frames per burst and more millimetres per pixel), then replays OUT and stores the results
computed from the shrunk bytes as its results.json, and replays once more to check that they
reproduce. Prints one line: frames and bytes before and after, and the largest relative change of
a point's numbers (what shrinking cost). Serial cassettes are copied unchanged.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
from pathlib import Path
from typing import Any

from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.errors import LabkitError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("shrink", help=COMMAND_SUMMARIES["shrink"],
                       description=__doc__.split("\n\n")[1] if __doc__ else None)
    p.add_argument("session", help="a recorded session folder")
    p.add_argument("out", help="new session folder (must not exist)")
    p.add_argument("--every", type=int, default=1, help="keep every k-th frame of each burst (default 1)")
    p.add_argument("--scale", type=float, default=1.0, help="scale the picture by this factor in (0, 1]")
    p.add_argument("--crop", help="X,Y,W,H in pixels of the recorded frames (before scaling)")
    p.add_argument("--quality", type=int, default=75, help="JPEG quality of the shrunk frames (default 75)")
    p.set_defaults(func=run)


def _crop(text: str | None) -> tuple[int, int, int, int] | None:
    if not text:
        return None
    try:
        x, y, w, h = (int(v) for v in text.split(","))
    except ValueError:
        raise LabkitError(f"--crop {text!r}: expected X,Y,W,H in pixels") from None
    return x, y, w, h


def _frame_cassettes(folder: Path) -> list[Path]:
    out = []
    for p in sorted(folder.glob("*.jsonl")):
        with p.open(encoding="utf-8") as f:
            first = f.readline()
        if '"labkit-frames"' in first:
            out.append(p)
    return out


def largest_change(before: list[dict[str, Any]], after: list[dict[str, Any]]) -> tuple[float, str]:
    """Largest relative change of a numeric point field, and its name (``step.key``)."""
    worst, name = 0.0, ""
    for a, b in zip(before, after, strict=False):
        for key, va in a.items():
            vb = b.get(key)
            if isinstance(va, float) and isinstance(vb, float) and va != 0 and math.isfinite(va):
                change = abs(vb / va - 1.0)
                if change > worst:
                    worst, name = change, f"{a.get('step')}.{key}"
    return worst, name


def _rewrite_point_events(events: Path, points: list[dict[str, Any]]) -> None:
    """The shrunk session's ``point`` events carry the points its shrunk bytes give (an exact
    replay holds events.jsonl against the cassettes, docs/explanation/replay.md)."""
    by_step = {p.get("step"): p for p in points}
    lines = []
    for line in events.read_text(encoding="utf-8").splitlines():
        doc = json.loads(line) if line.strip() else None
        is_point = isinstance(doc, dict) and doc.get("type") == "point"
        step = doc.get("point", {}).get("step") if is_point else None
        if step is not None and step in by_step:
            doc["point"] = by_step[step]
            line = json.dumps(doc, allow_nan=False, separators=(",", ":"))
        lines.append(line)
    tmp = events.with_suffix(".jsonl.tmp")
    tmp.write_text("\n".join(lines) + "\n", encoding="utf-8")
    tmp.replace(events)


def run(args: argparse.Namespace) -> int:
    from labkit.devices.camera.shrink import Shrink, shrink_cassette
    from labkit.protocols import get_protocol
    from labkit.protocols.replay import replay_session
    from labkit.protocols.runner import normalise
    from labkit.session.writer import write_json_atomic

    src, out = Path(args.session), Path(args.out)
    if not (src / "run.json").is_file():
        raise LabkitError(f"{src}: not a session (no run.json)")
    if out.exists():
        raise LabkitError(f"{out}: already exists; shrink writes a new folder")
    how = Shrink(args.every, args.scale, _crop(args.crop), args.quality)
    try:
        how.check()
    except ValueError as exc:
        raise LabkitError(f"shrink: {exc}") from None
    run_doc = json.loads((src / "run.json").read_text())
    protocol = get_protocol(run_doc["protocol"])
    hook = getattr(protocol, "shrunk_params", None)
    if hook is None:
        raise LabkitError(f"shrink: protocol {protocol.name!r} does not say how its parameters change with "
                          "fewer or smaller frames (a shrunk_params method)")
    recorded = json.loads((src / "results.json").read_text())
    shutil.copytree(src, out)
    try:
        report = []
        for cassette in _frame_cassettes(out / "cassettes"):
            before = json.loads(cassette.open(encoding="utf-8").readline())["settings"]["size"]
            report.append(shrink_cassette(cassette, how))
            after = json.loads(cassette.open(encoding="utf-8").readline())["settings"]["size"]
            # pixels per recorded pixel: the scaled width over the width before scaling (the crop's,
            # when cropped: a crop alone leaves millimetres per pixel as they were)
            scaled_from = how.crop[2] if how.crop is not None else int(before.split("x")[0])
            scale = int(after.split("x")[0]) / scaled_from
        if not report:
            raise LabkitError(f"{src}: no frame cassette to shrink")
        run_doc["params"] = hook(dict(run_doc["params"]), how, scale)
        run_doc["notes"] = (run_doc.get("notes") or "") + f" [shrunk from {src.name} by labkit shrink]"
        run_doc["shrunk_from"] = str(src)
        write_json_atomic(out / "run.json", run_doc)
        replayed = replay_session(out)
        results = normalise(replayed.outcome.results)
        if replayed.outcome.status != run_doc["status"] or results is None:
            raise LabkitError(f"shrink: the shrunk session replays as {replayed.outcome.status!r} "
                              f"({replayed.outcome.reason}); try a milder shrink")
        write_json_atomic(out / "results.json", results)
        _rewrite_point_events(out / "events.jsonl", results.get("points") or [])
        if "digests" in run_doc:  # the shrunk session's own files, as a session that ended records them
            from labkit.session.integrity import file_digests

            run_doc["digests"] = file_digests(out)
            write_json_atomic(out / "run.json", run_doc)
        check = replay_session(out)
        if not check.identical:
            raise LabkitError(f"shrink: the shrunk session does not reproduce its results: "
                              f"{check.differences[:2]}")
    except BaseException:
        shutil.rmtree(out, ignore_errors=True)
        raise
    worst, where = largest_change(recorded.get("points") or [], results.get("points") or [])
    frames = [sum(r["frames"][i] for r in report) for i in (0, 1)]
    size = [sum(r["bytes"][i] for r in report) for i in (0, 1)]
    print(json.dumps({"session": str(out), "frames": frames, "frame_bytes": size,
                      "session_bytes": sum(f.stat().st_size for f in out.rglob("*") if f.is_file()),
                      "largest_point_change": worst, "at": where}))
    return 0
