"""``labkit bench vision``: accuracy against synthetic ground truth versus processing time for each
quality setting (frame stride, region of interest, sub-pixel refinement), and throughput as a ratio
to decode-only reading of the same file (target: full analysis of a 1280x720 laser video at
>= 0.9x the decode speed, issue 28).

The clip is rendered by :mod:`labkit.synth` (seeded), written with mp4v, then read back: once
decode-only, then analysed per setting. Printed per setting: wall time, frames per second, the
ratio to decode-only, the process's CPU time (every thread's, the decoder's included) and its
ratio to decode-only's CPU (on a shared machine whose cores others take, the figure that means
something), and the errors of centre, semi-axes, rotation (and loops/b for trochoids).
Fixed costs (trace extraction and the pattern fit, independent of the clip length) are printed
apart, so the ratio for longer clips can be read off.

``--suite`` runs the robustness suite instead: >= 200 seeded cases drawn by the independent
renderer :mod:`labkit.footage` (never labkit.synth), rendered on demand into a cache folder,
analysed by ``labkit.vision`` and scored against their truth; it prints the pass rate per family
and difficulty, a confusion table of pattern kinds and the cases outside tolerance with verdict
ok (docs/explanation/robustness-suite.md, *Independent footage and the robustness suite*).

After the laser table comes the strobe table (``--strobe``, :mod:`labkit.cli.bench_vision_strobe`):
analysis time / clip duration for strobe clips of small and large bodies, with and without room
light, at 640x480 and 1080p, with each analysis's peak memory.
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from labkit.cli.parsers import command_parser

if TYPE_CHECKING:  # OpenCV and the vision stack load when the benchmark runs, not for --help
    from labkit.vision.laser.analyse import LaserQuality
    from labkit.vision.laser.result import LaserResult


def settings(roi: tuple[int, int, int, int]) -> list[tuple[str, LaserQuality]]:
    """The quality settings compared; ``roi`` is a box around the pattern (as a user would set)."""
    from labkit.vision.laser.analyse import LaserQuality

    return [
        ("full (stride 1, whole frame, sub-pixel, auto)", LaserQuality()),
        ("stride 1, luma forced (no colour probe)", LaserQuality(luma=True)),
        ("stride 1, 0.5 s chunks however long the clip", LaserQuality(max_chunks=10**6)),
        ("stride 1, ROI", LaserQuality(roi=roi)),
        ("stride 1, no sub-pixel", LaserQuality(subpixel=False)),
        ("stride 1, colour frames forced", LaserQuality(luma=False)),
        ("stride 2", LaserQuality(stride=2)),
        ("stride 4, ROI", LaserQuality(stride=4, roi=roi)),
        ("stride 8, ROI, no sub-pixel", LaserQuality(stride=8, roi=roi, subpixel=False)),
    ]


def pattern_roi(truth: dict, size: tuple[int, int], margin: float = 0.15) -> tuple[int, int, int, int]:
    """A box around the true pattern plus ``margin`` of its size and the drift."""
    cx, cy = truth["pattern"]["center_px"]
    r = truth["pattern"]["semi_axes_px"][0] * (1 + margin) + 20
    x0, y0 = max(0, int(cx - r)), max(0, int(cy - r))
    return x0, y0, min(size[0], int(cx + r)) - x0, min(size[1], int(cy + r)) - y0


def _size(text: str) -> tuple[int, int]:
    w, h = (int(v) for v in text.lower().split("x"))
    return w, h


def register(sub: argparse._SubParsersAction) -> None:
    parser = command_parser(sub, "vision", "video analysis: accuracy vs time, throughput vs decode-only",
                            __doc__)
    parser.add_argument("--size", type=_size, default=(1280, 720), help="WxH (default 1280x720)")
    parser.add_argument("--frames", type=int, default=300, help="clip length (default 300 = 10 s)")
    parser.add_argument("--pattern", choices=["ellipse", "epitrochoid", "hypotrochoid"], default="ellipse")
    parser.add_argument("--level", choices=["easy", "medium", "hard"], default="hard")
    parser.add_argument("--repeats", type=int, default=3,
                        help="interleaved rounds of every timing (default 3; the machine may be shared)")
    parser.add_argument("--keep", metavar="DIR", help="keep the rendered clip in DIR")
    strobe = parser.add_argument_group("strobe clips (docs/explanation/strobe-speed.md)")
    strobe.add_argument("--strobe", choices=["also", "only", "no"], default="also",
                        help="the strobe table after the laser one (also), alone (only) or not (no)")
    strobe.add_argument("--strobe-sizes", type=lambda t: [_size(v) for v in t.split(",")],
                        default=[(640, 480), (1920, 1080)], help="WxH,... (default 640x480,1920x1080)")
    strobe.add_argument("--strobe-frames", type=int, default=120,
                        help="frames per strobe clip (default 120 = 4 s)")
    suite = parser.add_argument_group("robustness suite (independent footage)")
    suite.add_argument("--suite", action="store_true",
                       help="run the robustness suite instead of the timing bench")
    suite.add_argument("--only", metavar="FAMILY",
                       help="one family: circle, ellipse, epitrochoid, hypotrochoid or strobe")
    suite.add_argument("--difficulty", choices=["easy", "medium", "hard"], help="one difficulty")
    suite.add_argument("--limit", type=int, metavar="N",
                       help="the first N cases (interleaved across families)")
    suite.add_argument("--json", metavar="OUT", help="write every case's outcome and the summary as JSON")
    suite.add_argument("--cache", metavar="DIR",
                       help="render cache (default $LABKIT_FOOTAGE_CACHE or ~/.cache/labkit/footage-suite)")
    parser.set_defaults(func=run)


def _timed(fn):
    """Wall time, the process's CPU time (all threads) and the value of ``fn()``."""
    t0, c0 = time.perf_counter(), time.process_time()
    value = fn()
    return time.perf_counter() - t0, time.process_time() - c0, value


def _spread(values: list[float]) -> str:
    """Median and range of a list of numbers, e.g. ``0.81x (0.74-0.86)``."""
    if len(values) == 1:
        return f"{values[0]:.2f}x"
    return f"{statistics.median(values):.2f}x ({min(values):.2f}-{max(values):.2f})"


def _errors(result: dict, truth: dict) -> str:
    """The pattern's errors against the truth, from the result's JSON."""
    from labkit.vision.shared.curves import rotation_error_deg

    p, t = result["pattern"], truth["pattern"]
    if p["type"] == "none":
        return f"no pattern ({p['reason']})"
    centre = math.dist(p["center_px"], t["center_px"])
    text = f"centre {centre:5.2f} px"
    if t["type"] in ("circle", "ellipse"):
        axes = max(abs(g / w - 1) for g, w in zip(p["semi_axes_px"], t["semi_axes_px"], strict=True))
        rot = rotation_error_deg(math.radians(p["rotation_deg"]), math.radians(t["rotation_deg"]), math.pi)
        text += f"  axes {100 * axes:5.2f} %  rotation {rot:5.2f} deg  ({p['type']})"
    else:
        b = abs((p["trochoid"] or {}).get("b", math.nan) - t["trochoid"]["b"])
        text += f"  loops {p['loops']}/{t['loops']}  b err {b:.3f}  ({p['type']})"
    return text


def run_suite(args: argparse.Namespace) -> int:
    """Render, analyse and score the suite's cases; print the summary."""
    import json

    from labkit.footage.suite import suite_cases
    from labkit.footage.suite_eval import default_cache, evaluate_case
    from labkit.footage.suite_report import format_summary, summarise

    try:
        cases = suite_cases(args.only, args.difficulty, args.limit)
    except ValueError as exc:
        print(f"labkit bench vision: {exc}")
        return 2
    cache = Path(args.cache) if args.cache else default_cache()
    print(f"robustness suite: {len(cases)} cases, footage cached in {cache}")
    outcomes = []
    t0 = time.perf_counter()
    for i, case in enumerate(cases, 1):
        outcome = evaluate_case(case, cache)
        outcomes.append(outcome)
        mark = "pass" if outcome.passed else "FAIL " + ",".join(outcome.failures)
        print(f"[{i:3d}/{len(cases)}] {case.name:32s} {case.kind:5s} {case.size[0]}x{case.size[1]:<5d} "
              f"-> {outcome.reported:16s} verdict {outcome.verdict or '-':9s} {mark}", flush=True)
    summary = summarise(outcomes)
    print()
    print(format_summary(summary))
    print(f"\n{len(cases)} cases in {time.perf_counter() - t0:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps({"summary": summary, "cases": [o.to_dict() for o in outcomes]},
                                              indent=1, default=str))
    return 0


def run(args: argparse.Namespace) -> int:
    if args.suite:
        return run_suite(args)
    from labkit.cli.bench_vision_strobe import run_strobe

    if args.strobe == "only":
        return run_strobe(args.strobe_sizes, args.strobe_frames, args.keep)
    rc = run_laser(args)
    if args.strobe == "also" and rc == 0:
        print()
        rc = run_strobe(args.strobe_sizes, args.strobe_frames, args.keep)
    return rc


def run_laser(args: argparse.Namespace) -> int:
    """The laser table: accuracy and time per quality setting, ratio to decode-only."""
    from labkit.synth import laser_truth, render_laser, write_clip
    from labkit.synth.presets import laser_pattern, laser_preset
    from labkit.vision.laser.analyse import LaserQuality, accumulate, analyse_laser
    from labkit.vision.laser.result import LaserResult
    from labkit.vision.shared.frames import open_frames

    w, h = args.size
    kw = {"ellipticity": 0.3, "rotation_deg": 35} if args.pattern == "ellipse" else {"loops": 4, "b": 0.3}
    spec = replace(
        laser_preset(args.level, args.size, seed=42),
        frames=args.frames,
        pattern=laser_pattern(args.pattern, args.size, **kw),
    )
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.keep) if args.keep else Path(tmp)
        path = folder / f"bench-{args.pattern}-{args.level}-{w}x{h}.mp4"
        t0 = time.perf_counter()
        write_clip(path, render_laser(spec), spec.fps, "mp4v", laser_truth(spec))
        print(
            f"clip: {path.name}, {args.frames} frames {w}x{h} mp4v, {args.level} footage "
            f"(rendered and written in {time.perf_counter() - t0:.1f} s)"
        )
        truth = laser_truth(spec)
        jobs = [("decode only (VideoCapture.read, BGR)", lambda: open_frames(path).decode_only()),
                ("decode only, luma plane", lambda: open_frames(path).decode_only(luma=True)),
                ("per-frame work only (decode + accumulate)",
                 lambda: accumulate(open_frames(path), LaserQuality()))]
        jobs += [(name, lambda q=q: analyse_laser(str(path), quality=q))
                 for name, q in settings(pattern_roi(truth, args.size))]
        times: dict[str, list[float]] = {name: [] for name, _ in jobs}
        ratios: dict[str, list[float]] = {name: [] for name, _ in jobs}
        cpus: dict[str, list[float]] = {name: [] for name, _ in jobs}
        cpu_ratios: dict[str, list[float]] = {name: [] for name, _ in jobs}
        results: dict[str, object] = {}
        decode = jobs[0][1]
        for _ in range(max(1, args.repeats)):
            # interleaved rounds, every job paired with a decode-only run just before it: the load
            # of a shared machine changes within seconds, so each ratio compares like with like
            for name, fn in jobs:
                t_dec, cpu_dec, results[jobs[0][0]] = _timed(decode)
                elapsed, cpu, results[name] = _timed(fn)
                times[name].append(elapsed)
                ratios[name].append(t_dec / elapsed)
                cpus[name].append(cpu)
                cpu_ratios[name].append(cpu_dec / cpu)
        n = results[jobs[0][0]]
        print(f"{args.repeats} interleaved rounds; time = best round; ratio = time of a decode-only run "
              "just before / this time: median (range); CPU = the process's CPU time, all threads (median), "
              "and its ratio likewise")
        print()
        header = (f"{'setting':46s} {'time s':>7s} {'fps':>6s} {'ratio to decode':>22s} {'fixed s':>7s} "
                  f"{'CPU s':>6s} {'CPU ratio':>22s}")
        print(f"{header}  accuracy")
        for name, _ in jobs:
            best, result = min(times[name]), results[name]
            fixed = f"{_fixed_cost(result):7.3f}" if isinstance(result, LaserResult) else f"{'':7s}"
            accuracy = _errors(result.to_json(), truth) if isinstance(result, LaserResult) else ""
            cpu = f"{statistics.median(cpus[name]):6.3f} {_spread(cpu_ratios[name]):>22s}"
            wall = f"{best:7.3f} {n / best:6.0f} {_spread(ratios[name]):>22s}"
            print(f"{name:46s} {wall} {fixed} {cpu}  {accuracy}")
        print()
        print("target: full analysis >= 0.9x decode-only (VideoCapture.read, BGR) on the same file "
              "(issue 28);")
        print("fixed = work left after the last frame is read (the fit; does not grow with clip length)")
    return 0


def _fixed_cost(result: LaserResult) -> float:
    return float(result.quality.evidence.get("fit_s", 0.0))
