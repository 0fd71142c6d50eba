"""Process CPU of laser trace extraction over one clip's chunks, against another copy of labkit.

Accumulates the clip's time chunks once (``labkit.vision.laser.analyse.accumulate``), then runs
:class:`labkit.vision.laser.analyse.TraceTracker` over every chunk, pass after pass, in child
processes and measures each child's whole-process CPU per pass (``time.process_time``: every
thread, OpenCV's thread pool included). With ``--compare-with DIR`` (a copy of labkit's source,
e.g. ``mkdir DIR && git archive REV labkit | tar -x -C DIR``) children of that copy alternate with
children of this tree round after round, so a busy machine slows both alike, and each in a process
of its own (one version's allocations and thread-pool state do not bill the other). The script
also checks that both give the same traces, bit for bit, for every chunk: every field of
``TracePoints``.

    python analysis/laser_trace_cpu.py /tmp/lb/bench-ellipse-hard-1280x720.mp4 --rounds 6 \\
        --passes 5 --compare-with /tmp/old

Prints ``uptime`` before and after (the machine is shared), best and median CPU per pass and the
ratios of the medians and of the bests; nothing is asserted (benchmarks print, tests do not time).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import fields
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]


def save_chunks(clip: str, path: Path) -> str:
    """The clip's chunks as accumulated by the analysis, into ``path`` (npz); returns a summary."""
    from labkit.vision.laser import analyse
    from labkit.vision.shared.frames import open_frames

    source = open_frames(clip)
    chunks = analyse.accumulate(source, analyse.LaserQuality())
    images = {f"image{i}": c.image for i, c in enumerate(chunks)}
    np.savez(path, frame_px=max(source.size), offsets=np.array([c.offset for c in chunks]),
             spans=np.array([(c.first, c.last) for c in chunks]), **images)
    return f"{len(chunks)} chunks of {chunks[0].image.shape}"


def child(chunk_file: Path, passes: int, traces_out: Path | None) -> None:
    """Run in a child: one warm-up pass, then ``passes`` timed passes; prints the CPU seconds
    (JSON) and writes the warm-up's traces to ``traces_out``."""
    from labkit.vision.laser import analyse

    data = np.load(chunk_file)
    frame_px = int(data["frame_px"])
    chunks = [analyse.Chunk(data[f"image{i}"], tuple(int(v) for v in off), int(a), int(b))
              for i, (off, (a, b)) in enumerate(zip(data["offsets"], data["spans"], strict=True))]

    def one_pass() -> list:
        tracker = analyse.TraceTracker(frame_px, True)
        return [tracker.extract(c) for c in chunks]

    traces = one_pass()
    if traces_out is not None:
        arrays = {f"{i}.{f.name}": np.asarray(np.nan if getattr(t, f.name) is None else getattr(t, f.name))
                  for i, t in enumerate(traces) for f in fields(t)}
        np.savez(traces_out, **arrays)
    cpu = []
    for _ in range(passes):
        start = time.process_time()
        one_pass()
        cpu.append(time.process_time() - start)
    print(json.dumps(cpu))


def differences(a: Path, b: Path) -> list[str]:
    """Arrays of two trace files that differ in dtype, shape or any byte."""
    x, y = np.load(a), np.load(b)
    if sorted(x.files) != sorted(y.files):
        return ["different chunks or fields"]
    return [k for k in x.files if x[k].dtype != y[k].dtype or x[k].shape != y[k].shape
            or x[k].tobytes() != y[k].tobytes()]


def run_child(tree: Path, chunk_file: Path, passes: int, traces_out: Path | None) -> list[float]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, __file__, "--child", str(chunk_file), "--passes", str(passes)]
    if traces_out is not None:
        cmd += ["--traces-out", str(traces_out)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clip", nargs="?", help="a laser clip (labkit bench vision --keep DIR writes one)")
    parser.add_argument("--rounds", type=int, default=6, help="child processes per tree, alternating")
    parser.add_argument("--passes", type=int, default=5, help="timed passes over all chunks per child")
    parser.add_argument("--compare-with", metavar="DIR", type=Path,
                        help="another copy of labkit's source tree (the folder holding labkit/)")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--traces-out", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child, args.passes, args.traces_out)
        return
    if not args.clip:
        parser.error("a clip is needed")
    trees = {"this tree": HERE}
    if args.compare_with:
        trees[f"labkit in {args.compare_with}"] = args.compare_with.resolve()
    print(f"uptime at start: {uptime()}")
    with tempfile.TemporaryDirectory() as tmp:
        chunk_file = Path(tmp) / "chunks.npz"
        print(f"{args.clip}: {save_chunks(args.clip, chunk_file)}")
        cpu: dict[str, list[float]] = {name: [] for name in trees}
        names = list(trees)
        for round_ in range(args.rounds):
            for name in names if round_ % 2 == 0 else names[::-1]:
                traces = Path(tmp) / f"traces{names.index(name)}.npz" if round_ == 0 else None
                cpu[name] += run_child(trees[name], chunk_file, args.passes, traces)
        for other in range(1, len(names)):
            differ = differences(Path(tmp) / "traces0.npz", Path(tmp) / f"traces{other}.npz")
            print(f"traces of {names[other]!r}: "
                  + ("identical bit for bit" if not differ else f"DIFFER: {differ[:8]}"))
    for name in names:
        print(f"  {name:40s} CPU per pass: best {1e3 * min(cpu[name]):7.1f} ms  "
              f"median {1e3 * statistics.median(cpu[name]):7.1f} ms  "
              f"({args.rounds} processes x {args.passes} passes)")
    mine = cpu[names[0]]
    for other in names[1:]:
        median = statistics.median(mine) / statistics.median(cpu[other])
        print(f"  ratio this tree / {other}: median {median:.3f}  best {min(mine) / min(cpu[other]):.3f}")
    print(f"uptime at end:   {uptime()}")


if __name__ == "__main__":
    main()
