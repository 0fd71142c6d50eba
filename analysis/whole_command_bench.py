"""Whole-process timings (hyperfine-style interleaved pairs): start-up and ``analyse laser``.

Start-up: ``labkit --help`` and every ``labkit CMD --help`` as fresh processes (issue 15: each under
0.3 s). Video: ``labkit analyse laser CLIP`` against a process that only decodes the clip (OpenCV
``VideoCapture.read`` on every frame, as ``labkit bench vision``'s decode-only reference), run in
alternating pairs so a busy machine slows both alike; the ratio is decode time / analyse time
(1.0: analysing costs no more than decoding; issue 15 asked >= 0.8 at 720p, issue 28 >= 0.9).

    python analysis/whole_command_bench.py                  # renders a 720p 10 s clip first
    python analysis/whole_command_bench.py --clip my.mp4 --pairs 7
    python analysis/whole_command_bench.py --help-only
    python analysis/whole_command_bench.py --video-only --compare-with /tmp/old   # before/after
    python analysis/whole_command_bench.py --video-only --pairs 0 --timeline 5    # where the time goes
    python analysis/whole_command_bench.py --video-only --no-bytecode    # compile labkit in every child
    python analysis/whole_command_bench.py --video-only --pairs 40 --quiet 0.3   # quiet moments only

Children keep compiled bytecode in a temporary folder, as an installed labkit has it, unless
``--no-bytecode`` (then a source tree under PYTHONDONTWRITEBYTECODE=1 is compiled in every child).

Prints medians and the range; nothing is asserted (benchmarks print, tests do not time). The
ratio is the median over the rounds of decode time / analyse time in the same round; "fastest
runs" divides the two fastest runs, the least disturbed ones on a machine that others load.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DECODE_ONLY = """
import sys, cv2
cap = cv2.VideoCapture(sys.argv[1])
n = 0
while True:
    ok, _ = cap.read()
    if not ok:
        break
    n += 1
cap.release()
print(n)
"""


DECODE_FRAMES = """
import sys
from labkit.vision.shared.frames import open_frames
print(open_frames(sys.argv[1]).decode_only())
"""


TIMELINE = """
import atexit, os, resource, sys, time
t0 = time.perf_counter()
marks = {}
import cv2
_Capture = cv2.VideoCapture
class Capture:  # stamps the first and the last frame any reader gets
    def __init__(self, *a, **k):
        self._c = _Capture(*a, **k)
    def __getattr__(self, name):
        return getattr(self._c, name)
    def _stamp(self, ok):
        if ok:
            now = time.perf_counter() - t0
            marks.setdefault("first_frame", now)
            marks["last_frame"] = now
        return ok
    def read(self, *a):
        r = self._c.read(*a)
        self._stamp(r[0])
        return r
    def grab(self):
        return self._stamp(self._c.grab())
cv2.VideoCapture = Capture
def report():  # registered first, so it runs after every other atexit handler
    marks["exit_handlers_done"] = time.perf_counter() - t0
    print("@@TIMELINE@@", time.time(), marks, file=sys.stderr)
atexit.register(report)
sys.argv = ["labkit", "analyse", "laser", sys.argv[1]]
from labkit.cli import main
code = main()
marks["command_done"] = time.perf_counter() - t0
sys.exit(code)
"""


def timeline(clip: Path, runs: int, trees: list[str | None]) -> None:
    """Where the whole process spends its time: start to the first frame, the last frame to the
    end of the command, and the interpreter's exit after the atexit handlers (median of ``runs``,
    alternating the copies of labkit in ``trees``; None is the one on the current path)."""
    import ast

    rows: dict[str | None, list[dict]] = {t: [] for t in trees}
    for tree in trees:  # warm-up: page cache and bytecode
        subprocess.run([sys.executable, "-c", TIMELINE, str(clip)], capture_output=True, env=child_env(tree),
                       cwd=tempfile.gettempdir())
    for i in range(runs):
        for tree in trees if i % 2 == 0 else trees[::-1]:
            start = time.time()
            proc = subprocess.run([sys.executable, "-c", TIMELINE, str(clip)], capture_output=True, text=True,
                                  env=child_env(tree), cwd=tempfile.gettempdir())
            end = time.time()
            line = proc.stderr.rpartition("@@TIMELINE@@")[2].strip()
            stamp, _, marks = line.partition(" ")
            m = ast.literal_eval(marks)
            rows[tree].append({"to first frame": m["first_frame"],
                               "frames": m["last_frame"] - m["first_frame"],
                               "last frame to result": m["command_done"] - m["last_frame"],
                               "interpreter exit": end - float(stamp), "whole": end - start})
    print(f"analyse laser {clip.name}: where the process spends its time, median (range) of {runs} runs "
          f"(load average {os.getloadavg()[0]:.1f})")
    for tree, runs_of in rows.items():
        parts = "  ".join(f"{k} {statistics.median(r[k] for r in runs_of):.3f} "
                          f"({min(r[k] for r in runs_of):.3f}-{max(r[k] for r in runs_of):.3f})"
                          for k in runs_of[0])
        print(f"  {tree or 'this labkit'}: {parts} s")


def cpu_of_child(argv: list[str], env: dict[str, str] | None = None) -> tuple[float, float, float | None]:
    """(wall, CPU user + system, cores other processes kept busy meanwhile) of one run of
    ``argv``; CPU time is what load from other jobs disturbs least. The other processes' load is
    the machine's busy time (``/proc/stat``) less the child's own, over the run's wall time
    (None where ``/proc/stat`` is not there)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    busy_before = machine_busy_s()
    t = wall(argv, env)
    busy_after = machine_busy_s()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if busy_before is None or busy_after is None:
        return t, cpu, None
    others = max(0.0, busy_after - busy_before - cpu) / t
    return t, cpu, others


def machine_busy_s() -> float | None:
    """CPU-seconds every core of the machine has been busy since boot (``/proc/stat``: all but
    idle and iowait), or None off Linux."""
    try:
        with open("/proc/stat") as f:
            fields = [int(v) for v in f.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def wait_for_quiet(max_cores: float, deadline: float) -> float | None:
    """Wait until the other processes keep fewer than ``max_cores`` cores busy over half a second
    (or ``deadline``, a ``time.monotonic`` value, passes); returns that load (None off Linux)."""
    while True:
        b0, t0 = machine_busy_s(), time.monotonic()
        time.sleep(0.5)
        b1 = machine_busy_s()
        if b0 is None or b1 is None:
            return None
        load = (b1 - b0) / (time.monotonic() - t0)
        if load < max_cores or time.monotonic() > deadline:
            return load


REPO = Path(__file__).resolve().parents[1]


#: where the children keep compiled bytecode (None: as the environment says; see ``--no-bytecode``)
BYTECODE_PREFIX: str | None = None


def child_env(tree: str | None = None) -> dict[str, str]:
    """Environment of a timed child: labkit from ``tree`` (default: this repository). Children run
    in a neutral folder, since ``python -m``/``-c`` put the current folder first on sys.path.

    With ``BYTECODE_PREFIX``, every child keeps compiled bytecode there (PYTHONPYCACHEPREFIX), as
    an installed package has it (pip compiles at install): a source tree run with
    PYTHONDONTWRITEBYTECODE=1 (as on the project's shared machine) otherwise compiles labkit's
    modules from source in every process, about 17 ms before the first frame and 22 ms for the fit
    side (measured with ``compile``), which no installed labkit pays. Every child, decode-only
    included, gets the same setting; the first (warm-up) round writes the bytecode."""
    env = dict(os.environ, PYTHONPATH=str(tree or REPO))
    if BYTECODE_PREFIX is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = BYTECODE_PREFIX
    return env


def wall(argv: list[str], env: dict[str, str] | None = None) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, env=env or child_env(),
                          cwd=tempfile.gettempdir())
    dt = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(argv)} failed ({proc.returncode}): {proc.stderr.strip()[-400:]}")
    return dt


def help_times(repeats: int) -> None:
    from labkit.cli import COMMANDS
    from labkit.cli.bench import BENCHES

    argvs = [[]] + [[c] for c in COMMANDS] + [["bench", b] for b in BENCHES]
    print(f"start-up: `labkit ... --help` as a fresh process, median of {repeats} (load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    worst = worst_cpu = 0.0
    for argv in argvs:  # warm-up: bytecode
        wall([sys.executable, "-m", "labkit", *argv, "--help"])
    for argv in argvs:
        runs = [cpu_of_child([sys.executable, "-m", "labkit", *argv, "--help"]) for _ in range(repeats)]
        med = statistics.median(w for w, _, _ in runs)
        cpu = statistics.median(c for _, c, _ in runs)
        worst, worst_cpu = max(worst, med), max(worst_cpu, cpu)
        print(f"  labkit {' '.join(argv + ['--help']):28s} wall {med:6.3f} s  CPU {cpu:6.3f} s")
    print(f"  slowest: wall {worst:.3f} s, CPU {worst_cpu:.3f} s (target < 0.3 s)")


def clip_for(args: argparse.Namespace, tmp: Path) -> Path:
    if args.clip:
        return Path(args.clip)
    clip = tmp / "clip720.mp4"
    subprocess.run([sys.executable, "-m", "labkit", "synth", "laser", str(clip), "--size", "1280x720",
                    "--frames", "300", "--level", "hard", "--pattern", args.pattern], check=True,
                   capture_output=True)
    return clip


def analyse_pairs(clip: Path, pairs: int, compare_with: str | None = None, quiet: float | None = None,
                  max_wait_s: float = 0.0) -> None:
    """Interleaved rounds of the two decode-only processes and ``labkit analyse laser`` (and, with
    ``compare_with``, the same command from another copy of labkit, e.g. the previous commit).
    With ``quiet`` (cores): each round waits until other processes keep fewer cores than that
    busy, only rounds in which every job ran with less than ``quiet`` cores taken by others count
    (a shared machine's quiet moments), and rounds run until ``pairs`` such rounds are in or
    ``max_wait_s`` has passed."""
    jobs = {
        "decode-only, labkit.vision.shared.frames (bench vision's reference)":
            [sys.executable, "-c", DECODE_FRAMES, str(clip)],
        "decode-only, bare cv2 read loop": [sys.executable, "-c", DECODE_ONLY, str(clip)],
        "labkit analyse laser": [sys.executable, "-m", "labkit", "analyse", "laser", str(clip)],
    }
    envs = {name: child_env() for name in jobs}
    if compare_with:
        name = f"labkit analyse laser from {compare_with}"
        jobs[name] = [sys.executable, "-m", "labkit", "analyse", "laser", str(clip)]
        envs[name] = child_env(compare_with)
    for name, argv in jobs.items():  # warm the page cache and numba/OpenCV caches
        wall(argv, envs[name])
    times: dict[str, list[float]] = {name: [] for name in jobs}
    cpu: dict[str, list[float]] = {name: [] for name in jobs}
    others: list[float] = []  # the most cores other processes took during any job of a kept round
    order = list(jobs)
    deadline = time.monotonic() + max_wait_s
    tried = 0
    while len(times[order[0]]) < pairs:
        if quiet is not None:
            if time.monotonic() > deadline:
                break
            wait_for_quiet(quiet, deadline)
        turn = order if tried % 2 == 0 else order[::-1]
        runs = {name: cpu_of_child(jobs[name], envs[name]) for name in turn}
        tried += 1
        busiest = max((o for _, _, o in runs.values() if o is not None), default=None)
        if quiet is not None and busiest is not None and busiest >= quiet:
            continue
        for name, (t, c, _) in runs.items():
            times[name].append(t)
            cpu[name].append(c)
        if busiest is not None:
            others.append(busiest)
    kept = len(times[order[0]])
    if kept == 0:
        print(f"no round of {tried} ran with other processes below {quiet} cores; nothing to report")
        return
    load = (f"other processes kept {min(others):.2f}-{max(others):.2f} cores busy (most in any job of "
            "a round)" if others else f"load average {os.getloadavg()[0]:.1f} at the end")
    print(f"analyse laser {clip.name} as a whole process, {kept} interleaved rounds"
          f"{f' of {tried} (rounds with others above {quiet} cores left out)' if quiet is not None else ''} "
          f"({load}; {os.cpu_count()} cores):")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"  {name:62s} median {med:.3f} s  range {min(ts):.3f}-{max(ts):.3f} s "
              f"({min(ts) / med:.2f}-{max(ts) / med:.2f} of its median); "
              f"CPU {statistics.median(cpu[name]):.3f} s")
    for analysed in [n for n in order if n.startswith("labkit analyse laser")]:
        for name in order[:2]:
            ratios = [d / a for d, a in zip(times[name], times[analysed], strict=True)]
            cpu_ratios = [d / a for d, a in zip(cpu[name], cpu[analysed], strict=True)]
            fastest = min(times[name]) / min(times[analysed])
            print(f"  {analysed} vs {name}: {statistics.median(ratios):.2f}x "
                  f"(range {min(ratios):.2f}-{max(ratios):.2f}; fastest runs {fastest:.2f}x; target >= 0.9); "
                  f"CPU {statistics.median(cpu_ratios):.2f}x ({min(cpu_ratios):.2f}-{max(cpu_ratios):.2f})")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clip", help="video to analyse (default: render a 1280x720 10 s clip)")
    ap.add_argument("--pattern", default="ellipse", help="synthetic pattern when rendering (default ellipse)")
    ap.add_argument("--pairs", type=int, default=5, help="interleaved decode/analyse pairs (default 5)")
    ap.add_argument("--repeats", type=int, default=3, help="runs per --help timing (default 3)")
    ap.add_argument("--quiet", type=float, metavar="CORES",
                    help="count only rounds in which other processes kept fewer than CORES cores busy, "
                         "waiting before each round for such a moment; --pairs such rounds (Linux; e.g. 0.3)")
    ap.add_argument("--max-wait", type=float, default=600.0, metavar="S",
                    help="with --quiet: stop after S seconds, with the quiet rounds found (default 600)")
    ap.add_argument("--help-only", action="store_true", help="only the start-up timings")
    ap.add_argument("--video-only", action="store_true", help="only the analyse laser pairs")
    ap.add_argument("--timeline", type=int, metavar="RUNS", default=0,
                    help="also time start-up, frames, the work after the last frame and the exit")
    ap.add_argument("--compare-with", metavar="PYTHONPATH",
                    help="also time `analyse laser` from this copy of labkit "
                         "(e.g. an unpacked `git archive HEAD~1 labkit`)")
    ap.add_argument("--no-bytecode", action="store_true",
                    help="run the children with the environment's bytecode setting (with "
                         "PYTHONDONTWRITEBYTECODE=1: labkit compiled from source in every process); "
                         "default: compiled bytecode kept in a temporary folder, as installed")
    args = ap.parse_args()
    global BYTECODE_PREFIX
    with tempfile.TemporaryDirectory() as prefix:
        if not args.no_bytecode:
            BYTECODE_PREFIX = prefix
        setting = os.environ.get("PYTHONDONTWRITEBYTECODE", "")
        print("bytecode: " + (f"as the environment says (PYTHONDONTWRITEBYTECODE={setting!r})"
                              if args.no_bytecode else
                              "compiled once into a temporary folder (PYTHONPYCACHEPREFIX), as installed"))
        return run(args)


def run(args: argparse.Namespace) -> int:
    if not args.video_only:
        help_times(args.repeats)
    if not args.help_only:
        with tempfile.TemporaryDirectory() as tmp:
            clip = clip_for(args, Path(tmp))
            if args.pairs:
                analyse_pairs(clip, args.pairs, args.compare_with, args.quiet, args.max_wait)
            if args.timeline:
                timeline(clip, args.timeline, [None] + ([args.compare_with] if args.compare_with else []))
    return 0


if __name__ == "__main__":
    sys.exit(main())
