"""``labkit bench io``: how fast labkit parses device bytes and replays recorded sessions.

Two measurements, each printed with the ratio it is about (no pass/fail):

* parser throughput: frames (or lines) per second for every protocol whose driver
  registered a typical frame with :func:`labkit.devices.base.register_parser_benchmark`;
* replay speed: a session of ``--minutes`` (default 10) of emulated traffic - a labkit_tach
  tachometer streaming at 10 Hz and an MT-SICS balance polled with ``SI`` once a second,
  both read by the real drivers - is recorded through ``record://sim://...`` on a virtual
  clock, then replayed through ``replay://...?mode=timed`` on a fresh virtual clock by the
  same drivers. It prints the wall time and the ratio of session time to wall time
  (target: 10 min in < 10 s, ratio >= 60) and whether the replayed readings equal the
  recorded ones.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from labkit.devices.registry import driver_class, parser_benchmarks
from labkit.emulators import use_emulation
from labkit.io.clock import Clock, VirtualClock
from labkit.io.ports import open_port
from labkit.readings import Reading

TACH_URL = "sim://labkit_tach?seed=2&plant=bench-io&role=rotor_tach&rate_hz=10"
BALANCE_URL = "sim://mtsics?seed=3&plant=bench-io&role=balance"
TACH_SERIAL = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1, "timeout": 0.2}
BALANCE_SERIAL = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1, "timeout": 0.5}
POLL_PERIOD_S = 1.0


# ---- parser throughput ------------------------------------------------------------------
def parser_rate(parse: Callable[[bytes], Any], sample: bytes, budget_s: float = 0.2,
                repeats: int = 3) -> float:
    """Best-of-``repeats`` calls per second of ``parse(sample)``, each run ~``budget_s`` long."""
    n = 1
    while True:  # size a batch that takes ~budget_s
        start = time.perf_counter()
        for _ in range(n):
            parse(sample)
        elapsed = time.perf_counter() - start
        if elapsed >= budget_s / 4 or n >= 1 << 24:
            break
        n *= 4
    best = elapsed / n
    for _ in range(repeats - 1):
        start = time.perf_counter()
        for _ in range(n):
            parse(sample)
        best = min(best, (time.perf_counter() - start) / n)
    return 1.0 / best if best > 0 else float("inf")


def bench_parsers(budget_s: float) -> list[dict[str, Any]]:
    rows = []
    for protocol, (sample, parse) in sorted(parser_benchmarks().items()):
        try:
            rate = parser_rate(parse, sample, budget_s)
            rows.append({"protocol": protocol, "frames_per_s": rate, "us_per_frame": 1e6 / rate,
                         "frame_bytes": len(sample)})
        except Exception as exc:  # noqa: BLE001 - a broken sample is reported, not fatal
            rows.append({"protocol": protocol, "error": f"{type(exc).__name__}: {exc}"})
    return rows


# ---- replay speed -----------------------------------------------------------------------
@dataclass
class SessionResult:
    tach_readings: list[Reading]
    balance_readings: list[Reading]


def run_session(clock: Clock, tach_url: str, balance_url: str, seconds: float) -> SessionResult:
    """The benchmark's session: stream the tachometer, poll the balance every second."""
    tach_port = open_port(tach_url, clock=clock, **TACH_SERIAL)
    balance_port = open_port(balance_url, clock=clock, **BALANCE_SERIAL)
    tach = driver_class("tachometer", "labkit_tach")(tach_port, clock, name="rotor_tach")
    balance = driver_class("balance", "mtsics")(balance_port, clock, name="balance")
    start = clock.now()
    polled: list[Reading] = []
    try:
        next_poll = start
        while next_poll - start < seconds:
            clock.sleep_until(next_poll)
            polled.append(balance.read())
            next_poll += POLL_PERIOD_S
        clock.sleep_until(start + seconds)
        streamed = tach.readings_since(float("-inf"))
    finally:
        tach.close()
        balance.close()
    return SessionResult(streamed, polled)


def count_events(folder: Path) -> int:
    return sum(sum(1 for _ in p.open(encoding="utf-8")) - 1 for p in folder.glob("*.jsonl"))


def timed_session(tach_url: str, balance_url: str, seconds: float) -> tuple[Any, float]:
    """:func:`run_session` on a fresh virtual clock, and the wall seconds it took."""
    wall = time.perf_counter()
    result = run_session(VirtualClock(), tach_url, balance_url, seconds)
    return result, time.perf_counter() - wall


def bench_replay(minutes: float, folder: Path) -> dict[str, Any]:
    seconds = minutes * 60.0
    tach_cassette, balance_cassette = folder / "rotor_tach.jsonl", folder / "balance.jsonl"
    with use_emulation() as emulation:
        emulation.plant("bench-io").set_duty(0.6, 0.0)  # the rotor spins up: readings change
        recorded, record_wall = timed_session(
            f"record://{TACH_URL}&cassette={tach_cassette}&port=rotor_tach",
            f"record://{BALANCE_URL}&cassette={balance_cassette}&port=balance", seconds)
    replayed, replay_wall = timed_session(
        f"replay://{tach_cassette}?mode=timed", f"replay://{balance_cassette}?mode=timed", seconds)
    return {
        "session_s": seconds,
        "tach_readings": len(recorded.tach_readings),
        "balance_readings": len(recorded.balance_readings),
        "cassette_events": count_events(folder),
        "cassette_bytes": sum(p.stat().st_size for p in folder.glob("*.jsonl")),
        "record_wall_s": record_wall,
        "replay_wall_s": replay_wall,
        "replay_ratio": seconds / replay_wall if replay_wall > 0 else float("inf"),
        "readings_identical": recorded == replayed,
    }


# ---- output -----------------------------------------------------------------------------
def print_report(parsers: list[dict[str, Any]], replay: dict[str, Any] | None) -> None:
    print("parser throughput (one typical frame per protocol, best of 3)")
    print(f"  {'protocol':<12} {'frames/s':>12} {'us/frame':>9} {'bytes':>6}")
    for row in parsers:
        if "error" in row:
            print(f"  {row['protocol']:<12} error: {row['error']}")
        else:
            print(f"  {row['protocol']:<12} {row['frames_per_s']:>12,.0f} {row['us_per_frame']:>9.2f} "
                  f"{row['frame_bytes']:>6}")
    if replay is None:
        return
    r = replay
    print(f"replay of a {r['session_s']:.0f} s session (labkit_tach 10 Hz stream + mtsics SI every "
          f"{POLL_PERIOD_S:g} s, real drivers)")
    print(f"  recorded: {r['tach_readings']} tach readings, {r['balance_readings']} balance readings, "
          f"{r['cassette_events']} cassette events, {r['cassette_bytes'] / 1e6:.2f} MB")
    print(f"  record through record://sim:// on a VirtualClock: {r['record_wall_s']:.2f} s wall")
    print(f"  replay timed on a VirtualClock: {r['replay_wall_s']:.2f} s wall -> "
          f"{r['replay_ratio']:.0f}x real time (target >= 60x)")
    print(f"  replayed readings identical to the recording: {'yes' if r['readings_identical'] else 'NO'}")


def run(args: argparse.Namespace) -> int:
    parsers = bench_parsers(args.parser_budget)
    replay = None
    if args.minutes > 0:
        if args.keep:
            folder = Path(args.keep)
            folder.mkdir(parents=True, exist_ok=True)
            replay = bench_replay(args.minutes, folder)
        else:
            with tempfile.TemporaryDirectory(prefix="labkit-bench-io-") as tmp:
                replay = bench_replay(args.minutes, Path(tmp))
    if args.json:
        print(json.dumps({"parsers": parsers, "replay": replay}, indent=2))
    else:
        print_report(parsers, replay)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("io", help="parser throughput and replay speed (ratios)",
                            description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--minutes", type=float, default=10.0,
                        help="length of the recorded session to replay (0: parsers only)")
    parser.add_argument("--parser-budget", type=float, default=0.2, metavar="S",
                        help="seconds per parser timing run (default 0.2)")
    parser.add_argument("--keep", metavar="DIR", help="keep the generated cassettes in DIR")
    parser.add_argument("--json", action="store_true", help="print the numbers as JSON")
    parser.set_defaults(func=run)


def main(argv: list[str] | None = None) -> int:
    """``python -m labkit.cli.bench_io``: the benchmark without loading every other command."""
    import sys

    parser = argparse.ArgumentParser(prog="labkit bench")
    register(parser.add_subparsers(dest="bench"))
    return run(parser.parse_args(["io", *(sys.argv[1:] if argv is None else argv)]))


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
