"""Memory of `labkit run` and `labkit replay` against the number of points, and the bytes each
device's cassette takes per second of run (issue 28, deliverable 2; docs/reference/session-size.md).

Runs the speed sweep of the emulated Fig. 5.25 rig (`speeds_rpm=6000:20000:n=N`, `up_down`,
`record_s=0.5`, virtual clock) at two sizes, each `labkit run` and then `labkit replay` in its
own process, and prints each one's peak resident memory (the kernel's ``ru_maxrss`` of that
child), the ratio of the two sizes (flat memory: close to 1 while the points grow by the size
ratio) and each cassette's bytes per second of run (the recorded run's clock, not the wall).
``--real-seconds S`` also records a short sweep on the real clock (5 steps, ~25 s) and
extrapolates its motor cassette's bytes per second to 10 minutes.

    python analysis/session_size_bench.py                     # 100 and 300 points (~8 min)
    python analysis/session_size_bench.py --sizes 50 200 --real
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "rigs" / "emulated-fig525.toml"


def measured(argv: list[str]) -> tuple[int, float, float]:
    """(exit status, peak RSS in MB, wall seconds) of ``python -m labkit ARGV`` in its own process
    (its stderr to a file: a long run warns a lot, and a full pipe would stop it)."""
    start = time.perf_counter()
    with tempfile.TemporaryFile() as errors:
        child = subprocess.Popen([sys.executable, "-m", "labkit", *argv], stdout=subprocess.DEVNULL,
                                 stderr=errors)
        _, status, usage = os.wait4(child.pid, 0)
        child.returncode = os.waitstatus_to_exitcode(status)
        if child.returncode != 0:
            errors.seek(0)
            sys.stderr.write(errors.read().decode(errors="replace")[-2000:])
    return child.returncode, usage.ru_maxrss / 1024, time.perf_counter() - start


def run_seconds(session: Path) -> float:
    """How long the run lasted on its own clock: the last time in its cassettes."""
    from labkit.io.cassette import CassetteReader

    last = 0.0
    for path in (session / "cassettes").glob("*.jsonl"):
        for event in CassetteReader(path):
            last = max(last, float(event["t"]))
    return last


def cassette_rates(session: Path, seconds: float) -> dict[str, dict[str, float]]:
    return {p.stem: {"bytes": p.stat().st_size, "bytes_per_s": p.stat().st_size / seconds}
            for p in sorted((session / "cassettes").glob("*.jsonl"))}


def folder_bytes(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def one_size(points: int, root: Path) -> dict:
    sessions = root / f"n{points}"
    argv = ["run", str(RIG), "speed-sweep", "--set", f"speeds_rpm=6000:20000:n={points}",
            "--set", "up_down=true", "--set", "record_s=0.5", "--sessions", str(sessions),
            "--no-progress", "--yes", "--clock", "virtual"]
    status, run_mb, run_wall = measured(argv)
    session = next(sessions.iterdir())
    rstatus, replay_mb, replay_wall = measured(["replay", str(session)])
    seconds = run_seconds(session)
    return {"points": 2 * points - 1, "run_exit": status, "run_peak_mb": run_mb, "run_wall_s": run_wall,
            "replay_exit": rstatus, "replay_peak_mb": replay_mb, "replay_wall_s": replay_wall,
            "run_seconds": seconds, "session_bytes": folder_bytes(session),
            "cassettes": cassette_rates(session, seconds)}


def real_clock(root: Path) -> dict:
    sessions = root / "real"
    argv = ["run", str(RIG), "speed-sweep", "--set", "speeds_rpm=6000:14000:n=5", "--set", "record_s=1",
            "--set", "zero=start", "--sessions", str(sessions), "--no-progress", "--yes", "--clock", "real"]
    status, run_mb, wall = measured(argv)
    session = next(sessions.iterdir())
    seconds = run_seconds(session)
    rates = cassette_rates(session, seconds)
    return {"run_exit": status, "run_seconds": seconds, "cassettes": rates,
            "motor_mb_per_10_min": rates["rotor_motor"]["bytes_per_s"] * 600 / 1e6}


def report(rows: list[dict], real: dict | None) -> None:
    print("speed sweep, emulated Fig. 5.25 rig, up_down, record_s=0.5, virtual clock; "
          "each command in its own process")
    print(f"  {'points':>6} {'run s':>8} {'run MB':>7} {'replay MB':>9} {'replay exit':>11} "
          f"{'session MB':>10}  cassette bytes per second of run")
    for r in rows:
        rates = ", ".join(f"{k} {v['bytes_per_s']:,.0f}" for k, v in r["cassettes"].items())
        print(f"  {r['points']:>6} {r['run_seconds']:>8.0f} {r['run_peak_mb']:>7.0f} "
              f"{r['replay_peak_mb']:>9.0f} {r['replay_exit']:>11} "
              f"{r['session_bytes'] / 1e6:>10.1f}  {rates}")
    if len(rows) >= 2:
        small, large = rows[0], rows[-1]
        print(f"  points x{large['points'] / small['points']:.1f}: run peak memory x"
              f"{large['run_peak_mb'] / small['run_peak_mb']:.2f}, replay peak memory x"
              f"{large['replay_peak_mb'] / small['replay_peak_mb']:.2f}")
    if real is not None:
        rates = ", ".join(f"{k} {v['bytes_per_s']:,.0f}" for k, v in real["cassettes"].items())
        print(f"real clock, 5-step sweep, {real['run_seconds']:.0f} s (exit {real['run_exit']}): "
              f"bytes per second {rates}; motor cassette for 10 minutes: "
              f"{real['motor_mb_per_10_min']:.1f} MB (target < 20 MB)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 300],
                        help="speeds per sweep direction (points = 2N-1 with up_down)")
    parser.add_argument("--real", action="store_true", help="also a ~25 s real-clock recording")
    parser.add_argument("--keep", type=Path, help="keep the sessions under this folder")
    parser.add_argument("--json", type=Path, help="write the numbers as JSON here")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        root = args.keep or Path(tmp)
        rows = [one_size(n, root) for n in args.sizes]
        real = real_clock(root) if args.real else None
    report(rows, real)
    if args.json:
        args.json.write_text(json.dumps({"sizes": rows, "real": real}, indent=2) + "\n")
    return 0 if all(r["replay_exit"] == 0 and r["run_exit"] == 0 for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
