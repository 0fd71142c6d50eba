"""Where the laser analysis spends its CPU beyond decoding (issue 28; docs/explanation/vision-throughput.md).

Analyses one clip several times and prints, per run: the CPU of each stage measured in the thread
that runs it (trace extraction, the first half's classification, histograms, gathering), the whole
process's CPU (every thread) and its minor page faults, beside the same for decoding and
accumulating alone. Make the benchmark's clip with ``labkit bench vision --keep DIR``.

    python analysis/laser_worker_profile.py DIR/bench-ellipse-hard-1280x720.mp4 --runs 5

Two readings to keep apart: a thread's clock misses the work OpenCV hands to its own thread pool
(blur, morphology, arithmetic on large images), so per-stage figures undercount OpenCV-heavy
stages; and a stage's cost moves with the allocation pattern (a large array freed and allocated
again may come back as fresh pages, each page faulted and zeroed), so compare two versions of a
stage by the process's CPU over several runs, not by one stage's thread clock.
"""

from __future__ import annotations

import argparse
import functools
import resource
import time
from collections import defaultdict
from collections.abc import Callable

from labkit.vision.laser import analyse, gather, pattern
from labkit.vision.shared.frames import open_frames

STAGES: dict[str, list[float]] = defaultdict(lambda: [0, 0.0])


def _timed(name: str, fn: Callable) -> Callable:
    """``fn`` adding its calling thread's CPU time to ``STAGES[name]``."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        start = time.thread_time()
        try:
            return fn(*args, **kwargs)
        finally:
            STAGES[name][0] += 1
            STAGES[name][1] += time.thread_time() - start

    return wrapper


def _instrument() -> None:
    """Wrap the stages where :func:`labkit.vision.laser.analyse.analyse_laser` looks them up."""
    analyse.trace_points = _timed("trace extraction (trace_points)", analyse.trace_points)
    analyse.grey_histogram = _timed("exposure histograms", analyse.grey_histogram)
    analyse.scene_measures = _timed("scene measures (main thread)", analyse.scene_measures)
    pattern.preliminary = _timed("first half's classification", pattern.preliminary)
    gather.GatheredTrace.add = _timed("gathering points", gather.GatheredTrace.add)


def _faults() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


def _measure(label: str, work: Callable[[], object]) -> None:
    faults, cpu, wall = _faults(), time.process_time(), time.perf_counter()
    work()
    print(f"{label:28s} wall {time.perf_counter() - wall:6.3f} s  CPU {time.process_time() - cpu:6.3f} s  "
          f"minor faults {_faults() - faults:7d}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clip", help="a laser clip (labkit bench vision --keep DIR writes one)")
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    analyse.analyse_laser(args.clip)  # imports and first-use costs out of the way
    _instrument()
    for _ in range(args.runs):
        _measure("decode + accumulate",
                 lambda: analyse.accumulate(open_frames(args.clip), analyse.LaserQuality()))
        _measure("full analysis", lambda: analyse.analyse_laser(args.clip))
    print(f"\nper full analysis, each stage's own thread's CPU (mean of {args.runs} runs):")
    for name, (calls, seconds) in sorted(STAGES.items(), key=lambda item: -item[1][1]):
        print(f"  {name:36s} {calls / args.runs:5.1f} calls  {1e3 * seconds / args.runs:7.1f} ms")


if __name__ == "__main__":
    main()
