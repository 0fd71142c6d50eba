"""``labkit bench sweep``: how a stability map scales, in this process, on a local process pool
and on a real Dask cluster on this machine.

Starts ``dask scheduler`` and N single-threaded ``dask worker`` processes on 127.0.0.1 (what a
lab starts on its own machines; nothing listens beyond loopback), runs the same Table 5.3 map
in process, on a pool of N processes and on the N Dask workers, and prints each one's speed-up
over the in-process map, measured in one run. Every engine is warmed first (numba's compiled
kernels loaded in every process) so that the table compares the sweep, not the start-up.
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

LOOPBACK = "127.0.0.1"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sweep", help="stability-map speed-up: in process, process pool, Dask on loopback")
    p.add_argument("--ratios", type=int, default=300,
                   help="tau_S/tau_C ratios of the map, 11 points each (default 300: 3300 points)")
    p.add_argument("--cycles", type=int, default=100, help="drive periods per point (default 100)")
    p.add_argument("--workers", default="1,2", help="worker counts to measure (default 1,2)")
    p.add_argument("--timeout", type=float, default=60.0, help="seconds to wait for the cluster to start")
    p.set_defaults(func=main)


def _dask(*args: str) -> list[str]:
    return [sys.executable, "-m", "distributed.cli.dask_" + args[0], *args[1:]]


class LoopbackCluster:
    """``dask scheduler`` and ``workers`` single-threaded ``dask worker`` processes on loopback."""

    def __init__(self, workers: int, timeout_s: float) -> None:
        self.workers, self.timeout_s = workers, timeout_s
        self.folder = tempfile.TemporaryDirectory(prefix="labkit-bench-sweep-")
        self.procs: list[subprocess.Popen] = []
        self.address = ""

    def __enter__(self) -> LoopbackCluster:
        info = Path(self.folder.name) / "scheduler.json"
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        self.procs.append(subprocess.Popen(_dask("scheduler", "--host", LOOPBACK, "--port", "0",
                                                 "--no-dashboard", "--scheduler-file", str(info)), **quiet))
        deadline = time.monotonic() + self.timeout_s
        while not info.exists() or not info.read_text().strip():
            if time.monotonic() > deadline or self.procs[0].poll() is not None:
                self.__exit__()
                raise RuntimeError("the Dask scheduler did not start")
            time.sleep(0.1)
        self.address = json.loads(info.read_text())["address"]
        env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
        for _ in range(self.workers):
            self.procs.append(subprocess.Popen(
                _dask("worker", self.address, "--nthreads", "1", "--nworkers", "1", "--host", LOOPBACK,
                      "--no-dashboard", "--no-nanny"), env=env, **quiet))
        return self

    def wait_for_workers(self, client) -> None:
        client.wait_for_workers(self.workers, timeout=self.timeout_s)

    def __exit__(self, *exc: object) -> None:
        for proc in reversed(self.procs):
            if proc.poll() is None:
                proc.terminate()
        for proc in self.procs:
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        self.folder.cleanup()


def _timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main(args: argparse.Namespace) -> int:
    from distributed import Client

    from labkit.numerics import stability_map
    from labkit.numerics.sweep import run_sweep

    counts = [int(n) for n in args.workers.split(",") if n.strip()]
    ratios = [0.6 * i / max(1, args.ratios - 1) for i in range(args.ratios)]
    points = stability_map.map_points(ratios)
    evaluate = stability_map.Evaluator(args.cycles)
    print(f"Table 5.3 map: {len(points)} points x {args.cycles} cycles, {os.cpu_count()} cores")
    run_sweep(points[:8], evaluate, progress=False)  # numba's kernels compiled / loaded here
    serial = _timed(lambda: run_sweep(points, evaluate, progress=False))
    print(f"in process: {serial:.2f} s (1.00x)")
    print("workers | pool | Dask, 16-point tasks | Dask, sized tasks | Dask sized / pool")
    for n in counts:
        pool = _timed(lambda n=n: run_sweep(points, evaluate, workers=n, progress=False))
        with LoopbackCluster(n, args.timeout) as cluster:
            with Client(cluster.address, set_as_default=False) as client:
                cluster.wait_for_workers(client)
                client.run(lambda: run_sweep(points[:8], evaluate, progress=False) and None)  # warm
            fixed = _timed(lambda: run_sweep(points, evaluate, chunk=16, scheduler=cluster.address,
                                             progress=False))
            sized = _timed(lambda: run_sweep(points, evaluate, scheduler=cluster.address, progress=False))
        print(f"{n:7d} | {serial / pool:4.2f}x | {serial / fixed:19.2f}x | {serial / sized:16.2f}x | "
              f"{pool / sized:.2f}")
    return 0
